"""Sessions for the pose tests: a small emulated recording with truth, and a textureless one."""

import numpy as np
import pytest
from emulated_sessions import REDUCED, record_emulated

from davis_io.session.recorder import record
from davis_io.types import EVENT_DTYPE, Frame, Packet, SourceInfo


@pytest.fixture(scope="session")
def emulated_session(tmp_path_factory):
    """A reduced emulated room session (blurred frames, noisy events) and its intrinsics."""
    return record_emulated(tmp_path_factory.mktemp("poses") / "room", **REDUCED)


class _FlatSource:
    """Six uniform grey frames with a few random events: nothing COLMAP can match."""

    def __init__(self, width=64, height=48, frames=6):
        self.info = SourceInfo(camera="DAVIS346", serial="T", width=width, height=height)
        rng = np.random.default_rng(0)
        self.packets = []
        for i in range(frames):
            start = i * 20_000
            events = np.zeros(50, EVENT_DTYPE)
            events["t"] = np.sort(rng.integers(start, start + 20_000, 50))
            events["x"], events["y"] = rng.integers(0, width, 50), rng.integers(0, height, 50)
            events["p"] = rng.choice([-1, 1], 50)
            image = np.full((height, width), 500, np.uint16)
            frame = Frame(image, start + 2_000, start + 12_000, start, start + 14_000)
            self.packets += [Packet(events=events), Packet(frames=[frame])]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return None

    def __iter__(self):
        return iter(self.packets)


@pytest.fixture
def textureless_session(tmp_path):
    """A recorded session whose frames are uniform grey."""
    record(_FlatSource(), tmp_path / "flat", bins=4)
    return tmp_path / "flat"
