"""Bins in light time: each frame's lead adds up the stream from its stretch's first exposure."""

from dataclasses import replace

import numpy as np
import pytest
from session_fakes import HEIGHT, WIDTH, ListSource, synthetic_packets

from davis_io.session import Session, contrast_bins
from davis_io.session.calibration import default_calibration
from davis_io.session.recorder import record

ON, OFF = 0.3, 0.2
LATENCY_US = 700


@pytest.fixture
def recorded(tmp_path):
    packets = synthetic_packets(5, seed=11)
    record(ListSource(packets), tmp_path / "s", bins=2, exposure_us=4_000)
    calibration = replace(
        default_calibration(0.25, "test"),
        threshold_on=ON,
        threshold_off=OFF,
        latency_us=LATENCY_US,
    )
    return tmp_path / "s", np.concatenate([p.events for p in packets]), calibration


def _change(events, t0, t1):
    """Hand count: each pixel's ON events times ON less its OFF events times OFF, t0 < t < t1."""
    inside = events[(events["t"] > t0) & (events["t"] < t1)]
    change = np.zeros((HEIGHT, WIDTH))
    for event in inside:
        change[event["y"], event["x"]] += ON if event["p"] > 0 else -OFF
    return change


def test_each_lead_is_the_last_one_with_its_exposure_and_the_events_between(recorded):
    folder, events, calibration = recorded
    with Session.open(folder) as session:
        bins = contrast_bins(session, 2, calibration)
        table = session.frames_table()
    starts = table.exposure_start_us + LATENCY_US
    ends = table.exposure_end_us + LATENCY_US
    np.testing.assert_array_equal(bins.stretch, [0, 0, 0, 0, 0])
    np.testing.assert_array_equal(bins.lead[0], 0.0)
    for index in range(1, 5):
        between = _change(events, ends[index - 1], starts[index])
        assert np.abs(between).sum() > 1.0
        expected = bins.lead[index - 1] + bins.calibrated[index - 1].sum(axis=0) + between
        np.testing.assert_allclose(bins.lead[index], expected, atol=1e-5)


def test_a_gap_between_exposures_or_a_lost_exposure_starts_a_new_stretch(recorded, monkeypatch):
    folder, _, calibration = recorded
    with Session.open(folder) as session:
        table = session.frames_table()
        gap = [[int(table.exposure_end_us[1]) + 900, int(table.exposure_start_us[2]) - 100]]
        monkeypatch.setattr(session, "event_gaps", lambda: np.array(gap, np.int64))
        bins = contrast_bins(session, 2, calibration)
        np.testing.assert_array_equal(bins.stretch, [0, 0, 1, 1, 1])
        np.testing.assert_array_equal(bins.lead[2], 0.0)
        assert np.abs(bins.lead[3]).sum() > 0
        lost = table.events_lost.copy()
        lost[3] = True
        monkeypatch.setattr(session, "frames_table", lambda: replace(table, events_lost=lost))
        monkeypatch.setattr(session, "event_gaps", lambda: np.zeros((0, 2), np.int64))
        bins = contrast_bins(session, 2, calibration)
    np.testing.assert_array_equal(bins.stretch, [0, 0, 0, 1, 2])
    np.testing.assert_array_equal(bins.lead[3:], 0.0)
