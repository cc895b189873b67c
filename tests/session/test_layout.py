"""``session.h5`` follows the layout table of README.md (the contract with the trainer)."""

import h5py
import numpy as np
from session_fakes import HEIGHT, WIDTH, ListSource, synthetic_packets

from davis_io.session import Session, SessionPoses
from davis_io.session.recorder import record
from davis_io.types import IMU_DTYPE, TRIGGER_DTYPE, Packet


def test_every_dataset_has_the_documented_dtype_and_shape(tmp_path):
    packets = synthetic_packets(3)
    imu = np.zeros(5, IMU_DTYPE)
    imu["t"] = np.arange(5) * 1_000
    triggers = np.zeros(2, TRIGGER_DTYPE)
    triggers["t"], triggers["kind"] = [1_000, 5_000], [8, 9]
    packets.insert(1, Packet(imu=imu, triggers=triggers))
    record(ListSource(packets), tmp_path / "s", bins=4)
    with Session.open(tmp_path / "s") as session:
        session.write_poses(
            4,
            SessionPoses(
                np.tile(np.eye(4), (3, 5, 1, 1)),
                np.ones((3, 5), bool),
                np.array([1.0, 1, 4, 3]),
                np.zeros(0),
                np.array([0.1, 5.0]),
            ),
        )
    frames, b = 3, 4
    events = sum(len(p.events) for p in packets)
    expected = {
        "events/t": (np.int64, (events,)),
        "events/x": (np.uint16, (events,)),
        "events/y": (np.uint16, (events,)),
        "events/p": (np.int8, (events,)),
        "frames/image": (np.uint16, (frames, HEIGHT, WIDTH)),
        "frames/exposure_start_us": (np.int64, (frames,)),
        "frames/exposure_end_us": (np.int64, (frames,)),
        "frames/readout_start_us": (np.int64, (frames,)),
        "frames/readout_end_us": (np.int64, (frames,)),
        "frames/events_lost": (np.bool_, (frames,)),
        "imu/t": (np.int64, (5,)),
        "imu/acc_g": (np.float32, (5, 3)),
        "imu/gyro_dps": (np.float32, (5, 3)),
        "imu/temperature_c": (np.float32, (5,)),
        "triggers/t": (np.int64, (2,)),
        "triggers/kind": (np.int8, (2,)),
        "bins/b4/split_us": (np.int64, (frames, b + 1)),
        "bins/b4/weights": (np.float64, (frames, b + 1)),
        "bins/b4/raw": (np.int16, (frames, b, HEIGHT, WIDTH)),
        "bins/b4/calibrated": (np.float32, (frames, b, HEIGHT, WIDTH)),
        "bins/b4/event_count": (np.int64, (frames,)),
        "poses/b4/c2w": (np.float64, (frames, b + 1, 4, 4)),
        "poses/b4/registered": (np.bool_, (frames, b + 1)),
        "poses/b4/intrinsics": (np.float64, (4,)),
        "poses/b4/bounds": (np.float64, (2,)),
    }
    with h5py.File(tmp_path / "s" / "session.h5", "r") as h5:
        for path, (dtype, shape) in expected.items():
            assert (h5[path].dtype, h5[path].shape) == (np.dtype(dtype), shape), path
        assert "distortion" in h5["poses/b4/intrinsics"].attrs
        assert h5["frames/image"].attrs["bit_depth"] == 10
        np.testing.assert_array_equal(h5["triggers/kind"][()], [8, 9])
        assert np.all(np.diff(h5["events/t"][()]) >= 0)
        assert h5["events/t"].compression == "lzf" and h5["events/p"].scaleoffset == 0


def test_what_is_written_after_recording_any_hdf5_build_reads(tmp_path):
    import shutil
    import subprocess

    from davis_io.session import default_calibration

    record(ListSource(synthetic_packets(3)), tmp_path / "s", bins=4)
    with Session.open(tmp_path / "s") as session:
        session.bins(2)  # bins for another b, computed from the stored events
        session.write_calibration(default_calibration(0.3, "stated"))
        session.write_poses(
            2,
            SessionPoses(
                np.tile(np.eye(4), (3, 3, 1, 1)),
                np.ones((3, 3), bool),
                np.array([1.0, 1, 4, 3]),
                np.zeros(0),
                np.array([0.1, 5.0]),
            ),
        )
        filters = session.filters()
    after = ("bins/b2/", "calibration/", "poses/")
    written_after = [n for names in filters.values() for n in names if n.startswith(after)]
    assert len(written_after) >= 5 + 4 + 4
    assert not [n for n in filters.get("lzf", []) if n.startswith(after)]
    assert filters["lzf"] and all(not n.startswith(after) for n in filters["lzf"])
    if shutil.which("h5dump"):  # Debian's hdf5-tools: a build with no LZF plug-in
        for name in written_after:
            shown = subprocess.run(
                ["h5dump", "-d", f"/{name}", str(tmp_path / "s" / "session.h5")],
                capture_output=True,
                text=True,
            )
            assert shown.returncode == 0 and "DATA" in shown.stdout, name
