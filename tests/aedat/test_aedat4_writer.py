"""AEDAT 4.0 writer: files open in dv-processing with the same content and read back exactly."""

import numpy as np
import pytest

from davis_io.aedat import Aedat4Reader, Aedat4Writer, Compression, open_recording, write_aedat4
from davis_io.errors import UsageError
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, SourceInfo

dv = pytest.importorskip("dv_processing")

INFO = SourceInfo(camera="DAVIS346", serial="00000042", width=346, height=260)


def _events(rng, n, t0):
    events = np.zeros(n, dtype=EVENT_DTYPE)
    events["t"] = t0 + np.sort(rng.integers(0, 50_000, n))
    events["x"] = rng.integers(0, 346, n)
    events["y"] = rng.integers(0, 260, n)
    events["p"] = rng.choice([-1, 1], n)
    return events


def _frame(rng, dtype, t0, bit_depth, channels=1):
    shape = (260, 346) if channels == 1 else (260, 346, channels)
    image = rng.integers(0, 1 << bit_depth, shape).astype(dtype)
    return Frame(
        image=image,
        exposure_start_us=t0 + 9_000,
        exposure_end_us=t0 + 13_773,
        readout_start_us=t0,
        readout_end_us=t0 + 23_652,
        bit_depth=bit_depth,
    )


def _imu(rng, n, t0):
    imu = np.zeros(n, dtype=IMU_DTYPE)
    imu["t"] = t0 + 1000 * np.arange(n)
    imu["acc_g"] = rng.normal(0, 1, (n, 3))
    imu["gyro_dps"] = rng.normal(0, 10, (n, 3))
    imu["temperature_c"] = 27.5
    return imu


def _triggers(t0):
    triggers = np.zeros(4, dtype=TRIGGER_DTYPE)
    triggers["t"] = t0 + np.array([0, 9_000, 13_773, 23_652])
    triggers["kind"] = [6, 8, 9, 7]
    return triggers


def _packets(seed=7, dtype=np.uint16, bit_depth=10):
    rng = np.random.default_rng(seed)
    t0 = 1_700_000_000_000_000
    return [
        Packet(
            events=_events(rng, 5000, t0),
            frames=[_frame(rng, dtype, t0, bit_depth)],
            imu=_imu(rng, 20, t0),
            triggers=_triggers(t0),
        ),
        Packet(
            events=_events(rng, 3000, t0 + 50_000),
            frames=[_frame(rng, dtype, t0 + 40_000, bit_depth)],
            imu=_imu(rng, 20, t0 + 20_000),
        ),
    ]


def _concat(packets, name):
    return np.concatenate([getattr(p, name) for p in packets])


@pytest.mark.parametrize("compression", [Compression.LZ4, Compression.ZSTD, Compression.NONE])
def test_written_file_reads_back_exactly(tmp_path, compression):
    packets = _packets()
    path = write_aedat4(packets, tmp_path / "out.aedat4", INFO, compression=compression)
    with open_recording(path) as reader:
        assert (reader.info.camera, reader.info.serial) == ("DAVIS346", "00000042")
        assert (reader.info.width, reader.info.height) == (346, 260)
        back = list(reader)
    for name in ("events", "imu", "triggers"):
        np.testing.assert_array_equal(_concat(back, name), _concat(packets, name))
    written = [f for p in packets for f in p.frames]
    read = [f for p in back for f in p.frames]
    assert len(read) == 2
    for ours, theirs in zip(read, written, strict=True):
        assert ours.image.dtype == np.uint16 and ours.bit_depth == 10
        np.testing.assert_array_equal(ours.image, theirs.image)
        assert ours == Frame(**{**theirs.__dict__, "image": ours.image})


def test_written_file_opens_in_dv_processing_with_same_content(tmp_path):
    packets = _packets()
    path = write_aedat4(packets, tmp_path / "out.aedat4", INFO)
    recording = dv.io.MonoCameraRecording(str(path))
    assert recording.getCameraName() == "DAVIS346_00000042"
    assert tuple(recording.getEventResolution()) == (346, 260)
    events = []
    while (batch := recording.getNextEventBatch()) is not None:
        events.append(batch.numpy())
    events = np.concatenate(events)
    ours = _concat(packets, "events")
    np.testing.assert_array_equal(events["timestamp"], ours["t"])
    np.testing.assert_array_equal(events["x"], ours["x"])
    np.testing.assert_array_equal(events["y"], ours["y"])
    np.testing.assert_array_equal(np.where(events["polarity"], 1, -1), ours["p"])
    for frame in [f for p in packets for f in p.frames]:
        theirs = recording.getNextFrame()
        # 10-bit values are stored left-aligned in 16U_C1 (value << 6), as DV's 16-bit images
        np.testing.assert_array_equal(theirs.image, frame.image << 6)
        assert theirs.timestamp == frame.exposure_start_us
        assert theirs.exposure.total_seconds() * 1e6 == frame.exposure_us
    assert recording.getNextFrame() is None
    imu = []
    while (batch := recording.getNextImuBatch()) is not None:
        imu += batch
    ours_imu = _concat(packets, "imu")
    np.testing.assert_array_equal([s.timestamp for s in imu], ours_imu["t"])
    np.testing.assert_array_equal(
        [[s.gyroscopeX, s.gyroscopeY, s.gyroscopeZ] for s in imu], ours_imu["gyro_dps"]
    )
    np.testing.assert_array_equal([s.temperature for s in imu], ours_imu["temperature_c"])
    triggers = recording.getNextTriggerBatch()
    assert [(t.timestamp, int(t.type)) for t in triggers] == _concat(packets, "triggers").tolist()


def test_eight_bit_and_colour_frames_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    gray = _frame(rng, np.uint8, 1000, 8)
    colour = _frame(rng, np.uint8, 50_000, 8, channels=3)
    path = write_aedat4([Packet(frames=[gray, colour])], tmp_path / "c.aedat4", INFO)
    with open_recording(path) as reader:
        read = [f for p in reader for f in p.frames]
    assert [f.image.dtype for f in read] == [np.uint8, np.uint8] and read[0].bit_depth == 8
    np.testing.assert_array_equal(read[0].image, gray.image)
    np.testing.assert_array_equal(read[1].image, colour.image)  # RGB in, RGB out
    recording = dv.io.MonoCameraRecording(str(path))
    recording.getNextFrame()
    # dv-processing sees OpenCV's BGR order: channel 0 is our blue
    np.testing.assert_array_equal(recording.getNextFrame().image, colour.image[..., ::-1])


def test_data_table_rows_point_at_payloads(tmp_path):
    path = write_aedat4(_packets(), tmp_path / "t.aedat4", INFO)
    with Aedat4Reader(path) as reader:
        rows = reader.data_table
        data = path.read_bytes()
        # 2 event packets + 2 frames + 2 IMU packets + 1 trigger packet
        assert len(rows) == 7
        for row in rows:  # DV convention: ByteOffset is the payload, header 8 bytes before it
            assert np.frombuffer(data[row.byte_offset - 8 : row.byte_offset], "<i4").tolist() == [
                row.stream_id,
                row.size,
            ]
        assert rows[0].num_elements == 5000
        assert reader.time_range[0] == 1_700_000_000_000_000


def test_empty_source_writes_a_valid_empty_file(tmp_path):
    path = write_aedat4([], tmp_path / "e.aedat4", INFO)
    with open_recording(path) as reader:
        assert reader.data_table == [] and list(reader) == []
    recording = dv.io.MonoCameraRecording(str(path))
    assert recording.getNextEventBatch() is None


def test_writer_refuses_a_frame_of_another_bit_depth(tmp_path):
    frame = _frame(np.random.default_rng(1), np.uint16, 0, 12)
    with Aedat4Writer(tmp_path / "d.aedat4", INFO) as writer, pytest.raises(UsageError):
        writer.write(Packet(frames=[frame]))
