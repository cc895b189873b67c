"""The real DAVIS346 AEDAT 4.0 recording: facts of its README and equality with dv-processing."""

import numpy as np
import pytest

from davis_io.aedat import Aedat4Reader, open_recording
from davis_io.summary import summarize
from davis_io.types import EVENT_DTYPE, TriggerKind

dv = pytest.importorskip("dv_processing")


def _read_all(path):
    with open_recording(path) as source:
        packets = list(source)
    events = np.concatenate([p.events for p in packets])
    frames = [f for p in packets for f in p.frames]
    imu = np.concatenate([p.imu for p in packets])
    triggers = np.concatenate([p.triggers for p in packets])
    return packets, events, frames, imu, triggers


def _dv_all(path):
    recording = dv.io.MonoCameraRecording(str(path))
    events, frames, imu, triggers = [], [], [], []
    while (batch := recording.getNextEventBatch()) is not None:
        events.append(batch.numpy())
    while (frame := recording.getNextFrame()) is not None:
        frames.append(frame)
    while (batch := recording.getNextImuBatch()) is not None:
        imu += batch
    while (batch := recording.getNextTriggerBatch()) is not None:
        triggers += batch
    return recording, np.concatenate(events), frames, imu, triggers


def test_summary_reports_the_fixture_readme_facts(aestream_aedat4):
    with open_recording(aestream_aedat4) as source:
        summary = summarize(source)
    assert (summary.format, summary.camera, summary.serial) == ("AEDAT 4.0", "DAVIS346", "00000104")
    assert (summary.width, summary.height) == (346, 260)
    assert summary.streams == ["events", "frames", "imu", "triggers"]
    assert summary.events.count == 117_667 and summary.on_events == 72_363
    assert summary.event_packets == 13 and summary.events.non_monotonic == 0
    assert (summary.events.first_us, summary.events.last_us) == (1633953690975950, 1633953691105949)
    assert summary.x_range == [0, 345] and summary.y_range == [0, 259]
    assert summary.frames.count == 3
    assert summary.frame_shapes == ["uint8 gray 260 x 346 (8-bit)"]
    assert summary.frame_exposure_starts_us == [
        1633953690976518,
        1633953691016518,
        1633953691056518,
    ]
    assert summary.frame_exposures_us == [4773, 4773, 4773]
    assert min(summary.frame_readouts_us) == 23_652
    assert summary.imu.count == 130
    # 130 samples, one every 1,000 µs: 129 intervals span 129,xxx µs
    assert summary.imu_rate_hz == pytest.approx(1000, rel=1e-3)
    assert summary.imu_mean_temperature_c == pytest.approx(27.8, abs=0.05)
    assert summary.triggers.count == 15
    assert summary.trigger_kinds == {
        "APS_FRAME_START": 3,
        "APS_FRAME_END": 4,
        "APS_EXPOSURE_START": 4,
        "APS_EXPOSURE_END": 4,
    }
    assert summary.time_range_us == [1633953690967091, 1633953691110744]
    assert summary.gaps == [] and summary.notes == []


def test_decoded_records_equal_dv_processing(aestream_aedat4):
    _, events, frames, imu, triggers = _read_all(aestream_aedat4)
    recording, dv_events, dv_frames, dv_imu, dv_triggers = _dv_all(aestream_aedat4)
    assert events.dtype == EVENT_DTYPE
    np.testing.assert_array_equal(events["t"], dv_events["timestamp"])
    np.testing.assert_array_equal(events["x"], dv_events["x"])
    np.testing.assert_array_equal(events["y"], dv_events["y"])
    np.testing.assert_array_equal(events["p"], np.where(dv_events["polarity"] == 1, 1, -1))
    assert len(frames) == len(dv_frames) == 3
    for ours, theirs in zip(frames, dv_frames, strict=True):
        assert ours.image.dtype == np.uint8 and ours.bit_depth == 8
        np.testing.assert_array_equal(ours.image, theirs.image)
        assert ours.exposure_start_us == theirs.timestamp  # dv-processing: start of exposure
        assert ours.exposure_us == theirs.exposure.total_seconds() * 1e6
        assert ours.position == (theirs.positionX, theirs.positionY)
    assert len(imu) == len(dv_imu) == 130
    np.testing.assert_array_equal(imu["t"], [s.timestamp for s in dv_imu])
    np.testing.assert_array_equal(
        imu["acc_g"], [[s.accelerometerX, s.accelerometerY, s.accelerometerZ] for s in dv_imu]
    )
    np.testing.assert_array_equal(
        imu["gyro_dps"], [[s.gyroscopeX, s.gyroscopeY, s.gyroscopeZ] for s in dv_imu]
    )
    np.testing.assert_array_equal(imu["temperature_c"], [s.temperature for s in dv_imu])
    np.testing.assert_array_equal(triggers["t"], [t.timestamp for t in dv_triggers])
    np.testing.assert_array_equal(triggers["kind"], [int(t.type) for t in dv_triggers])
    assert recording.getCameraName() == "DAVIS346_00000104"


def test_frame_times_match_the_triggers(aestream_aedat4):
    _, _, frames, _, triggers = _read_all(aestream_aedat4)
    by_kind = {kind: set(triggers["t"][triggers["kind"] == kind].tolist()) for kind in TriggerKind}
    # The trigger stream starts inside the first frame (3 FRAME_START for 4 FRAME_END): its start
    # of frame is end of frame minus readout, 1633953690990743 - 23652 = 1633953690967091.
    assert frames[0].readout_start_us == 1633953690967091
    assert {f.readout_start_us for f in frames[1:]} <= by_kind[TriggerKind.APS_FRAME_START]
    for frame in frames:
        assert frame.exposure_start_us in by_kind[TriggerKind.APS_EXPOSURE_START]
        assert frame.exposure_end_us in by_kind[TriggerKind.APS_EXPOSURE_END]
        assert frame.readout_end_us in by_kind[TriggerKind.APS_FRAME_END]
        assert frame.readout_start_us < frame.exposure_start_us < frame.exposure_end_us
        assert frame.exposure_end_us < frame.readout_end_us


def test_data_table_time_range_and_range_read(aestream_aedat4):
    _, events, frames, imu, _ = _read_all(aestream_aedat4)
    with Aedat4Reader(aestream_aedat4) as reader:
        assert len(reader.data_table) == 40  # one row per packet
        assert reader.time_range == (1633953690975950, 1633953691110744)
        start, end = 1633953691000000, 1633953691050000
        packets = list(reader.read_range(start, end))
        read_rows = len(packets)
    inside = (events["t"] >= start) & (events["t"] < end)
    got = np.concatenate([p.events for p in packets])
    np.testing.assert_array_equal(got, events[inside])
    assert got["t"].min() >= start and got["t"].max() < end
    assert [f.exposure_start_us for p in packets for f in p.frames] == [1633953691016518]
    assert sum(len(p.imu) for p in packets) == int(((imu["t"] >= start) & (imu["t"] < end)).sum())
    assert read_rows < 40  # the table let it skip packets outside the range
