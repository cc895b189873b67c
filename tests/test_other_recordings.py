"""Recordings made other ways than the emulator's default: the pipeline notices, assumes, fits.

One small session recorded as a DAVIS owner might: 30 ms exposures every 200 ms, events kept
only within 3 ms of an exposure (a recording made view by view), the camera held still for two
frames. Calibration, poses and a default fit must complete; what could not be measured is said.
"""

import json

import numpy as np
import pytest

from davis_io.calibration.consistency import THRESHOLD_RANGE
from davis_io.calibration.estimate import LATENCIES_US
from davis_io.emulator import EmulatedCamera
from davis_io.prepare import prepare_session
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.types import ColorFilter
from seenerf.model.config import FitConfig
from seenerf.train import fit_session

SMALL = dict(frames=8, test_views=1, baseline_m=0.18, width=173, height=130, focal_px=140.0)


@pytest.fixture(scope="module")
def view_by_view(tmp_path_factory):
    folder = tmp_path_factory.mktemp("other") / "view-by-view"
    camera = EmulatedCamera(
        "room",
        color_filter=ColorFilter.MONO,
        seed=5,
        exposure_us=30_000,
        frame_interval_us=200_000,
        event_window_us=3_000,
        still_frames=2,
        **SMALL,
    )
    record(camera, folder, bins=4)
    camera.write_truth(folder)
    lines = []
    prepare_session(folder, 4, log=lines.append)
    return folder, lines


def test_the_gaps_are_found_once_and_stored(view_by_view):
    folder, _ = view_by_view
    with Session.open(folder) as session:
        gaps = session.event_gaps()
        table = session.frames_table()
        assert session.manifest.event_gaps_us == gaps.tolist()
        # Between the exposures the camera moved in: 200 - 30 - 2 x 3 ms without an event.
        # Where the gyro shows it held still, no events is no loss: those stretches are not gaps.
        lengths = gaps[:, 1] - gaps[:, 0]
        assert len(gaps) >= 4 and np.sum((160_000 <= lengths) & (lengths <= 170_000)) >= 4
        assert not table.events_lost.any()  # no exposure lies in a gap
        inside = (gaps[:, None, 0] < table.exposure_end_us) & (
            gaps[:, None, 1] > table.exposure_start_us
        )
        assert not inside.any()


def test_the_preparation_says_each_step_and_how_long_it_took(view_by_view):
    _, lines = view_by_view
    assert any(line.startswith("sensor measured in ") for line in lines)
    assert any(line.startswith("poses estimated in ") for line in lines)
    # The thresholds are assumed but a response curve was fitted beside them: the latent
    # frames are made with the calibration's values and with the nominal ones, each named.
    for sensor in ("assumed", "nominal"):
        assert f"poses: latent frames ({sensor} sensor)" in lines
        assert f"poses: features ({sensor} sensor)" in lines
        stage = f"poses: latent frames ({sensor} sensor) "
        counted = [line for line in lines if line.startswith(stage)]
        assert counted[-1].startswith(f"{stage}8/8 in ")
        assert len(counted) == 4


def test_what_could_not_be_measured_is_assumed_and_said(view_by_view):
    folder, lines = view_by_view
    with Session.open(folder) as session:
        calibration = session.calibration()
    assert calibration.source == "assumed" and "thresholds" in calibration.assumed
    # The response was fitted beside those thresholds: not measured either.
    assert "response" in calibration.assumed and not calibration.response_linear
    assert any("thresholds not measured" in line for line in lines)
    # No stored value sits at a search bound.
    low, high = THRESHOLD_RANGE
    for value in (calibration.threshold_on, calibration.threshold_off):
        assert low * 1.05 < value < high * 0.95
    assert calibration.latency_us < max(LATENCIES_US)
    assert calibration.black_level >= 0 and calibration.saturation <= 1


def test_the_default_fit_completes_and_renders(view_by_view):
    folder, _ = view_by_view
    result = fit_session(folder, FitConfig.of(steps=3, warm_steps=10), log=lambda line: None)
    assert (result.run_dir / "renders" / "hdr").is_dir()
    # The response was not measured: the fit learns it with the MLPs.
    settings = json.loads((result.run_dir / "config.json").read_text())
    assert settings["rgb_response"] == "RgbCrf"
    assert result.summary.steps == 3 and result.summary.skipped_steps == 0
    assert "hdr" in result.metrics  # scored against the emulator's truth


def test_a_session_whose_every_exposure_lost_events_is_fitted_whole(view_by_view, tmp_path):
    import shutil

    from seenerf.data.session import load_training_data

    folder, _ = view_by_view
    copy = tmp_path / "dropped"
    shutil.copytree(folder, copy, ignore=shutil.ignore_patterns("fit", ".writer.lock"))
    manifest = json.loads((copy / "session.json").read_text())
    with Session.open(copy) as session:
        table = session.frames_table()
    # A stream that dropped out in every exposure: each is inside a gap.
    manifest["event_gaps_us"] = [
        [int(start) - 1, int(end) + 1]
        for start, end in zip(table.exposure_start_us, table.exposure_end_us, strict=True)
    ]
    (copy / "session.json").write_text(json.dumps(manifest))
    with Session.open(copy) as session:
        assert session.frames_table().events_lost.all()
    with pytest.warns(UserWarning, match="every frame's exposure lost events"):
        data = load_training_data(copy, 4)
    assert data.num_frames == len(table.exposure_us)
