"""summarize() over a hand-built source: counts, rates, gaps, order checks, empty input."""

import numpy as np
import pytest

from davis_io.summary import format_summary, summarize
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, SourceInfo


class ListSource:
    def __init__(self, packets):
        self.info = SourceInfo(
            camera="DAVIS240", serial="7", width=240, height=180, origin="emulator:test"
        )
        self._packets = packets

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return None

    def __iter__(self):
        return iter(self._packets)


def _events(times, x=0, y=0, p=1):
    events = np.zeros(len(times), dtype=EVENT_DTYPE)
    events["t"], events["x"], events["y"], events["p"] = times, x, y, p
    return events


def _source():
    first = _events([1000, 2000, 3000], x=[5, 7, 9], y=[1, 2, 3], p=[1, -1, 1])
    # 203,000 - 3,000 = 200,000 µs without events: one gap; 202,500 after 203,000 goes back
    second = _events([203_000, 202_500], x=[100, 6], y=[50, 0], p=[-1, -1])
    imu = np.zeros(3, dtype=IMU_DTYPE)
    imu["t"] = [0, 1000, 2000]
    imu["temperature_c"] = [30.0, 31.0, 32.0]
    triggers = np.array([(100, 6), (500, 7), (600, 7)], dtype=TRIGGER_DTYPE)
    frame = Frame(
        image=np.zeros((180, 240), np.uint16),
        exposure_start_us=400,
        exposure_end_us=900,
        readout_start_us=50,
        readout_end_us=1500,
    )
    return ListSource(
        [
            Packet(events=first, imu=imu, triggers=triggers, frames=[frame]),
            Packet(events=second, dropped_events=12, notes=["host queue overflow"]),
        ]
    )


def test_counts_ranges_and_rates():
    summary = summarize(_source())
    assert (summary.format, summary.camera, summary.width) == ("emulator", "DAVIS240", 240)
    assert summary.streams == ["events", "frames", "imu", "triggers"]
    assert summary.events.count == 5 and summary.on_events == 2 and summary.event_packets == 2
    assert (summary.events.first_us, summary.events.last_us) == (1000, 202_500)
    # 5 events over 202,500 - 1,000 = 201,500 µs
    assert summary.event_rate_hz == pytest.approx(5 / 0.2015)
    assert summary.x_range == [5, 100] and summary.y_range == [0, 50]
    assert summary.imu_rate_hz == pytest.approx(1000.0)  # 2 intervals in 2,000 µs
    assert summary.imu_mean_temperature_c == pytest.approx(31.0)
    assert summary.trigger_kinds == {"APS_FRAME_START": 1, "APS_FRAME_END": 2}
    assert summary.frame_exposures_us == [500] and summary.frame_readouts_us == [1450]
    assert summary.time_range_us == [0, 203_000]  # IMU at 0 .. last-but-one event
    assert summary.dropped_events == 12 and summary.notes == ["host queue overflow"]


def test_gaps_and_backward_timestamps_are_reported():
    summary = summarize(_source())
    assert summary.gaps == [[3000, 203_000]]
    assert summary.events.non_monotonic == 1
    text = format_summary(summary)
    assert "no events from 3000 to 203000 µs (200,000 µs)" in text
    assert "1 events timestamps go backwards" in text
    assert "12 events lost" in text


def test_empty_source():
    summary = summarize(ListSource([]))
    assert summary.packets == 0 and summary.events.count == 0 and summary.streams == []
    assert summary.event_rate_hz == 0.0 and summary.imu_mean_temperature_c is None
    assert summary.time_range_us is None
    assert "events      0 in 0 packets" in format_summary(summary)
    assert summary.to_dict()["events"]["duration_us"] == 0
