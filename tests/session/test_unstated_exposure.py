"""Frames that state no exposure get an assumed one, and the session says so."""

import dataclasses

import numpy as np
import pytest

from davis_io.aedat import write_aedat4
from davis_io.capture import CaptureRequest, record_capture
from davis_io.session import Session
from davis_io.session.unstated_exposure import LONE_FRAME_US, UnstatedExposures
from davis_io.types import EVENT_DTYPE, Frame, Packet, SourceInfo


def _frame(start_us: int, exposure_us: int = 0) -> Frame:
    return Frame(
        image=np.zeros((4, 5), np.uint16),
        exposure_start_us=start_us,
        exposure_end_us=start_us + exposure_us,
        readout_start_us=start_us,
        readout_end_us=start_us + exposure_us,
        bit_depth=10,
    )


def test_an_unstated_exposure_is_half_the_time_to_the_next_frame():
    unstated = UnstatedExposures()
    assert unstated.accept(_frame(1_000)) == []  # held until the next start is known
    ready = unstated.accept(_frame(201_000))
    assert [(f.exposure_start_us, f.exposure_end_us) for f in ready] == [(1_000, 101_000)]
    # The last frame takes the exposure assumed before it.
    (last,) = unstated.finish()
    assert (last.exposure_start_us, last.exposure_end_us) == (201_000, 301_000)
    assert unstated.assumed_us == [100_000, 100_000] and unstated.median_us == 100_000


def test_a_stated_exposure_passes_and_a_given_one_serves_the_rest():
    unstated = UnstatedExposures(given_us=40_000)
    stated = _frame(0, 25_000)
    assert unstated.accept(stated) == [stated]
    (given,) = unstated.accept(_frame(200_000))
    assert given.exposure_end_us - given.exposure_start_us == 40_000
    assert unstated.finish() == []
    assert UnstatedExposures().median_us is None


def test_a_lone_frame_and_a_frame_at_the_same_start_take_the_fallback():
    unstated = UnstatedExposures()
    unstated.accept(_frame(5_000))
    (first,) = unstated.accept(_frame(5_000))  # the next starts with it: no interval to halve
    assert first.exposure_end_us - first.exposure_start_us == LONE_FRAME_US
    (second,) = unstated.finish()
    assert second.exposure_end_us - second.exposure_start_us == LONE_FRAME_US


def _recording(path, starts_us=(0, 100_000, 200_000, 300_000)):
    rng = np.random.default_rng(3)
    packets = []
    for start, end in zip(starts_us, (*starts_us[1:], starts_us[-1] + 100_000), strict=True):
        events = np.zeros(200, EVENT_DTYPE)
        events["t"] = start + np.sort(rng.integers(0, end - start, 200))
        events["x"], events["y"] = rng.integers(0, 5, 200), rng.integers(0, 4, 200)
        events["p"] = rng.choice([-1, 1], 200)
        packets.append(Packet(events=events, frames=[_frame(start)]))
    info = SourceInfo(camera="DAVIS346", serial="1", width=5, height=4)
    return write_aedat4(packets, path, info)


@pytest.mark.parametrize(("given_us", "assumed_us"), [(None, 50_000), (20_000, 20_000)])
def test_a_replayed_file_without_exposures_is_binned_over_the_assumed_ones(
    tmp_path, given_us, assumed_us
):
    path = _recording(tmp_path / "no-exposure.aedat4")
    request = CaptureRequest(replay=path, exposure_us=given_us)
    result = record_capture(request, tmp_path / "session", bins=2)
    assert any("4 frames state no exposure" in warning for warning in result.warnings)
    with Session.open(result.folder) as session:
        assert session.manifest.exposure_assumed_us == assumed_us
        table = session.frames_table()
        np.testing.assert_array_equal(table.exposure_us, assumed_us)
        bins = session.bins(2)
        for k in range(4):
            start = k * 100_000
            inside = session.events_between(start, start + assumed_us)
            assert bins.event_count[k] == len(inside) > 0
    assert dataclasses.asdict(result.manifest)["exposure_assumed_us"] == assumed_us


class _Stopped(Exception):
    pass


def test_the_preparation_of_a_fit_says_the_exposures_were_assumed(tmp_path, monkeypatch):
    import davis_io.prepare as prepare

    path = _recording(tmp_path / "no-exposure.aedat4")
    result = record_capture(CaptureRequest(replay=path), tmp_path / "session", bins=2)

    def calibration_stops(*args, **kwargs):
        raise _Stopped

    monkeypatch.setattr(prepare, "session_calibration", calibration_stops)
    lines = []
    with pytest.raises(_Stopped):
        prepare.prepare_session(result.folder, 2, log=lines.append)
    assert lines[0].startswith("exposures assumed: the recording's frames state none")
    assert "50.0 ms (median)" in lines[0]


def test_the_last_frame_within_a_limit_is_released_by_the_next_ones_start(tmp_path):
    path = _recording(tmp_path / "no-exposure.aedat4", (0, 100_000, 300_000, 400_000))
    result = record_capture(CaptureRequest(replay=path, frames=2), tmp_path / "session", bins=2)
    with Session.open(result.folder) as session:
        assert session.frame_count == 2
        # Half of 100 ms, then half of the 200 ms to the third frame, which is not recorded.
        np.testing.assert_array_equal(session.frames_table().exposure_us, [50_000, 100_000])
