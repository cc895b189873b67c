"""Hand-built packet sources and synthetic streams for the session tests."""

import itertools
import time

import numpy as np

from davis_io.types import EVENT_DTYPE, Frame, Packet, SourceInfo

WIDTH, HEIGHT = 8, 6
FRAME_PERIOD_US = 10_000
EXPOSURE_START_US, EXPOSURE_END_US = 1_000, 5_000  # offsets inside each period


class ListSource:
    """A packet source over a list (or any iterable) of packets."""

    def __init__(self, packets, *, origin="emulator:test", width=WIDTH, height=HEIGHT):
        self.packets = packets
        self.info = SourceInfo(
            camera="DAVIS346", serial="T1", width=width, height=height, origin=origin
        )
        self.entered = self.exited = False

    def __enter__(self):
        self.entered = True
        return self

    def __exit__(self, *exc):
        self.exited = True

    def __iter__(self):
        return iter(self.packets)


def random_events(rng, t0_us, t1_us, count, width=WIDTH, height=HEIGHT):
    """``count`` sorted random events with t0 <= t < t1."""
    events = np.zeros(count, EVENT_DTYPE)
    events["t"] = np.sort(rng.integers(t0_us, t1_us, count))
    events["x"] = rng.integers(0, width, count)
    events["y"] = rng.integers(0, height, count)
    events["p"] = rng.choice([-1, 1], count)
    return events


def frame_at(index, value=None):
    """Frame ``index``: exposure [1000, 5000] µs into its 10 ms period, readout to 8000 µs."""
    t0 = index * FRAME_PERIOD_US
    image = np.full((HEIGHT, WIDTH), index if value is None else value, np.uint16)
    return Frame(
        image=image,
        exposure_start_us=t0 + EXPOSURE_START_US,
        exposure_end_us=t0 + EXPOSURE_END_US,
        readout_start_us=t0,
        readout_end_us=t0 + 8_000,
    )


def synthetic_packets(frames, *, seed=0, events_per_period=400):
    """Events of each 10 ms period, then that period's frame (as a camera delivers them)."""
    rng = np.random.default_rng(seed)
    packets = []
    for index in range(frames):
        t0 = index * FRAME_PERIOD_US
        events = random_events(rng, t0, t0 + FRAME_PERIOD_US, events_per_period)
        packets.append(Packet(events=events))
        packets.append(Packet(frames=[frame_at(index, value=500 + index)]))
    end = frames * FRAME_PERIOD_US
    packets.append(Packet(events=random_events(rng, end, end + 1_000, 10)))
    return packets


def endless_packets(with_frames):
    """An endless stream of 10 ms event packets, each followed by its frame if ``with_frames``.

    Frame ``k`` has pixel value ``k % 1000``; without frames the stream is paced by a short sleep.
    """
    rng = np.random.default_rng(0)
    for index in itertools.count():
        t0 = index * FRAME_PERIOD_US
        yield Packet(events=random_events(rng, t0, t0 + FRAME_PERIOD_US, 2_000))
        if with_frames:
            yield Packet(frames=[frame_at(index, value=index % 1000)])
        else:
            time.sleep(0.002)
