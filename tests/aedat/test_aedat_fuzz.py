"""Property-based fuzzing: readers raise only our typed errors, whatever the bytes."""

import tempfile
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_aedat2 import APS_3X2, DVS_AND_EXTERNAL, IMU
from test_aedat2 import HEADER as HEADER_2
from test_aedat31 import FRAME, IMU6, POLARITY, SPECIAL
from test_aedat31 import HEADER as HEADER_31

from davis_io.aedat import Compression, RecordingWarning, open_recording, write_aedat4
from davis_io.errors import DavisIOError
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, SourceInfo

FUZZ = settings(
    max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)


def _small_aedat4(compression):
    events = np.zeros(20, dtype=EVENT_DTYPE)
    events["t"] = np.arange(20)
    events["x"], events["y"], events["p"] = 3, 4, 1
    imu = np.zeros(2, dtype=IMU_DTYPE)
    triggers = np.zeros(2, dtype=TRIGGER_DTYPE)
    frame = Frame(
        image=np.arange(12, dtype=np.uint16).reshape(3, 4),
        exposure_start_us=2,
        exposure_end_us=5,
        readout_start_us=1,
        readout_end_us=9,
    )
    info = SourceInfo(camera="DAVIS346", serial="1", width=346, height=260)
    with tempfile.TemporaryDirectory() as folder:
        path = write_aedat4(
            [Packet(events=events, frames=[frame], imu=imu, triggers=triggers)],
            Path(folder) / "s.aedat4",
            info,
            compression=compression,
        )
        return path.read_bytes()


SEEDS = {
    "4.0-lz4": _small_aedat4(Compression.LZ4),
    "4.0-none": _small_aedat4(Compression.NONE),
    "3.1": HEADER_31 + POLARITY + SPECIAL + IMU6 + FRAME,
    "2.0": HEADER_2 + DVS_AND_EXTERNAL + IMU + APS_3X2,
}


def _read_everything(data: bytes) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "f.aedat"
        path.write_bytes(data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RecordingWarning)
            try:
                with open_recording(path) as source:
                    for _ in source:
                        pass
            except DavisIOError:
                pass


def _mutations(seed: bytes, first: int = 14):
    """Overwrite up to 8 bytes at or after ``first`` and optionally cut the file."""
    edits = st.lists(st.tuples(st.integers(first, len(seed) - 1), st.integers(0, 255)), max_size=8)
    return st.tuples(edits, st.integers(first, len(seed)))


def _aedat4_data_start(seed: bytes) -> int:
    """Magic (14 bytes), IOHeader size prefix (4) and IOHeader: mutate the packets after it."""
    return 18 + int.from_bytes(seed[14:18], "little")


def _apply(seed: bytes, edits, cut) -> bytes:
    data = bytearray(seed)
    for position, value in edits:
        data[position] = value
    return bytes(data[:cut])


@FUZZ
@given(_mutations(SEEDS["4.0-lz4"]))
def test_fuzz_aedat4_header_and_packets(mutation):
    _read_everything(_apply(SEEDS["4.0-lz4"], *mutation))


@FUZZ
@given(_mutations(SEEDS["4.0-lz4"], _aedat4_data_start(SEEDS["4.0-lz4"])))
def test_fuzz_aedat4_lz4_packets(mutation):
    _read_everything(_apply(SEEDS["4.0-lz4"], *mutation))


@FUZZ
@given(_mutations(SEEDS["4.0-none"], _aedat4_data_start(SEEDS["4.0-none"])))
def test_fuzz_aedat4_uncompressed(mutation):
    _read_everything(_apply(SEEDS["4.0-none"], *mutation))


@FUZZ
@given(_mutations(SEEDS["3.1"]))
def test_fuzz_aedat31(mutation):
    _read_everything(_apply(SEEDS["3.1"], *mutation))


@FUZZ
@given(_mutations(SEEDS["2.0"]))
def test_fuzz_aedat2(mutation):
    _read_everything(_apply(SEEDS["2.0"], *mutation))


@FUZZ
@given(
    st.sampled_from([b"#!AER-DAT4.0\r\n", b"#!AER-DAT3.1\r\n", b"#!AER-DAT2.0\r\n"]),
    st.binary(max_size=300),
)
def test_fuzz_random_bodies(magic, body):
    _read_everything(magic + body)
