import dataclasses
import json

import numpy as np
import pytest
from emulated_sessions import record_emulated

from davis_io.cli import main
from davis_io.errors import UsageError
from davis_io.poses import ColmapError, estimate_poses
from davis_io.poses.truth import compare_with_truth
from davis_io.session import Session
from davis_io.session.truth import load_truth


@pytest.fixture(scope="module")
def estimated(emulated_session):
    folder, lens = emulated_session
    report = estimate_poses(folder, b=4, lens=lens, force=True)
    return folder, report


def test_emulated_session_meets_the_pose_acceptance(estimated):
    folder, report = estimated
    assert report.total == 8 * 5
    assert report.registered_fraction >= 0.95
    with Session.open(folder) as session:
        poses, split_us = session.poses(4), session.bins(4).split_us
        truth = load_truth(session.truth_dir)
    errors = compare_with_truth(poses, split_us, truth)
    print(report.summary(), errors.median_rotation_deg, errors.median_translation_fraction)
    assert errors.median_rotation_deg < 1.0
    assert errors.median_translation_fraction < 0.02
    # Stored poses are proper rigid transforms and unregistered ones are flagged.
    rotations = poses.c2w[..., :3, :3]
    assert np.allclose(rotations @ np.swapaxes(rotations, -1, -2), np.eye(3), atol=1e-6)
    assert poses.registered.sum() == report.registered
    assert 0 < poses.bounds[0] < poses.bounds[1]
    assert np.allclose(poses.intrinsics, [280, 280, 172.5, 129.5])  # held fixed


@pytest.mark.slow
def test_full_benchmark_session_meets_the_pose_acceptance(tmp_path):
    # The benchmark session: 16 views x 5 latent frames at 346 x 260, the emulator's defaults.
    folder, lens = record_emulated(tmp_path / "room16", frames=16, test_views=2)
    report = estimate_poses(folder, b=4, lens=lens)
    assert report.registered_fraction >= 0.95
    with Session.open(folder) as session:
        errors = compare_with_truth(
            session.poses(4), session.bins(4).split_us, load_truth(session.truth_dir)
        )
    assert errors.median_rotation_deg < 1.0
    assert errors.median_translation_fraction < 0.02


def test_report_has_tracks_and_test_views(estimated):
    folder, report = estimated
    assert report.track_counts.shape == (8, 5)
    assert np.all(report.track_counts[report.track_counts > 0] >= 30)
    assert 0 < report.reprojection_error_px < 2.0
    assert report.strategy == report.tried[-1]
    assert (folder / "colmap" / "database.db").exists()
    saved = json.loads((folder / "colmap" / "report.json").read_text())
    assert saved["registered"] == report.registered


def test_stored_poses_are_reused_without_force(estimated):
    folder, report = estimated
    again = estimate_poses(folder, b=4)  # returns the stored report, COLMAP does not run
    assert again.registered == report.registered
    assert np.array_equal(again.track_counts, report.track_counts)


def test_poses_verb_prints_the_report(estimated, capsys):
    folder, report = estimated
    assert main(["poses", str(folder), "--bins", "4"]) == 0  # stored poses: no COLMAP run
    out = capsys.readouterr().out
    assert f"registered {report.registered}/40 latent frames" in out
    assert "tracks per view:" in out


def test_textureless_session_fails_with_advice(textureless_session, capsys):
    with pytest.raises(ColmapError, match="texture"):
        estimate_poses(textureless_session, b=4)
    assert main(["poses", str(textureless_session)]) == 1
    err = capsys.readouterr().err
    assert "seecap: error: poses:" in err and "Traceback" not in err and "texture" in err


def test_a_sensor_that_cannot_be_measured_is_one_warning_line(textureless_session, capsys):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert main(["poses", str(textureless_session)]) == 1
    err = capsys.readouterr().err
    assert "seecap: warning: the sensor could not be measured" in err
    assert "UserWarning" not in err and "Traceback" not in err


def test_a_disk_too_small_for_colmap_is_refused_before_it_starts(
    textureless_session, monkeypatch, capsys
):
    from collections import namedtuple

    import davis_io.session.writer as writer

    usage = namedtuple("usage", "total used free")
    # 6 frames x 5 latent frames of 64 x 48 pixels x 8 bytes (0.74 MB), plus the 16.78 MB kept
    # free: 17.5 MB.
    monkeypatch.setattr(writer.shutil, "disk_usage", lambda path: usage(0, 0, 10_000_000))
    assert main(["poses", str(textureless_session)]) == 1
    err = capsys.readouterr().err
    last = err.strip().splitlines()[-1]
    assert "Traceback" not in err and last.startswith("seecap: error: poses: ")
    assert "10.0 MB free" in last and "estimating poses (30 latent frames" in last
    assert "needs 18 MB (1 MB for its files and 17 MB to close them intact)" in last
    assert not (textureless_session / "colmap" / "images").exists()


def test_latent_frames_are_made_with_the_nominal_sensor_beside_a_doubtful_calibration():
    from davis_io.poses.estimate import _latent_sensors
    from davis_io.session import DEFAULT_THRESHOLD, SensorCalibration, default_calibration

    measured = SensorCalibration(0.3, 0.4)
    assert [label for label, _ in _latent_sensors(measured, None)] == ["measured"]
    doubtful = SensorCalibration(0.3, 0.4, assumed={"latency_us": "at its search's bound"})
    (_, first), (label, nominal) = _latent_sensors(doubtful, None)
    assert first is doubtful and label == "nominal"
    assert nominal.threshold_on == nominal.threshold_off == DEFAULT_THRESHOLD
    given = _latent_sensors(doubtful, 0.2)
    assert [(label, c.threshold) for label, c in given] == [("given", 0.2)]
    nothing = default_calibration(0.25, "no frames")
    assert [label for label, _ in _latent_sensors(nothing, None)] == ["default"]
    # Thresholds assumed, but a response curve fitted beside them: the nominal sensor too.
    curve = dict(response_value=np.array([0.1, 0.9]), response_log_exposure=np.array([-2.0, 0.0]))
    fitted = SensorCalibration(0.3, 0.3, source="assumed", assumed={"thresholds": "bound"}, **curve)
    assert [label for label, _ in _latent_sensors(fitted, None)] == ["assumed", "nominal"]
    empty = dict(response_value=np.zeros(0), response_log_exposure=np.zeros(0))
    plain = dataclasses.replace(fitted, **empty)
    assert [label for label, _ in _latent_sensors(plain, None)] == ["assumed"]


def test_poses_keep_the_better_of_the_measured_and_the_nominal_latent_frames(
    textureless_session, monkeypatch
):
    import davis_io.poses.estimate as estimate
    from davis_io.poses.colmap import SparseModel
    from davis_io.poses.nerfstudio import latent_frame_name
    from davis_io.poses.recovery import Outcome
    from davis_io.session import SensorCalibration

    b = 2
    with Session.open(textureless_session) as session:
        doubtful = SensorCalibration(0.3, 0.3, assumed={"latency_us": "at its profile's end"})
        session.write_calibration(doubtful)
        split_us, frames = session.bins(b).split_us, session.frame_count
    names = [[latent_frame_name(i, k) for k in range(b + 1)] for i in range(frames)]
    flat = [name for view in names for name in view]
    made_with = {}

    def reconstruct(session, b, label, calibration, folder, lens, progress):
        """COLMAP as it might answer: the nominal frames register 18 of 18, the measured 12."""
        made_with[label] = calibration.threshold
        (folder / "images").mkdir(parents=True, exist_ok=True)
        (folder / "images" / f"{label}.png").write_bytes(b"")
        registered = flat[: 12 if label == "measured" else 18]
        model = SparseModel(
            c2w={name: np.eye(4) for name in registered},
            intrinsics=np.array([50.0, 50.0, 31.5, 23.5]),
            distortion=np.zeros(0),
            points=np.zeros((10, 3)),
            track_counts={name: 5 for name in registered},
            bounds=np.array([1.0, 3.0]),
            reprojection_error_px=0.5,
        )
        succeeded = label == "nominal"
        outcome = Outcome(model, "exhaustive", succeeded, ("exhaustive",))
        return estimate._Trial(label, calibration, folder, names, split_us, outcome)

    monkeypatch.setattr(estimate, "_reconstruct", reconstruct)
    report = estimate_poses(textureless_session, b=b)
    assert made_with == {"measured": 0.3, "nominal": 0.3}
    assert report.latent_sensor == "nominal" and report.registered == 18
    assert report.compared["measured"]["registered"] == 12
    assert report.compared["nominal"]["mean_track_length"] == 9.0  # 18 x 5 / 10 points
    assert "latent frames kept: nominal" in report.summary()
    colmap = textureless_session / "colmap"
    assert [p.name for p in (colmap / "images").iterdir()] == ["nominal.png"]
    assert not (colmap / "nominal").exists()
    saved = json.loads((colmap / "report.json").read_text())
    assert saved["latent_sensor"] == "nominal" and set(saved["compared"]) == {"measured", "nominal"}


def test_poses_made_with_another_lens_are_estimated_again(textureless_session, monkeypatch):
    import davis_io.poses.estimate as estimate
    from davis_io.lens import Lens
    from davis_io.poses.colmap import SparseModel
    from davis_io.poses.nerfstudio import latent_frame_name
    from davis_io.poses.recovery import Outcome
    from davis_io.session import SensorCalibration

    b = 2
    with Session.open(textureless_session) as session:
        session.write_calibration(SensorCalibration(0.3, 0.3))
        split_us, frames = session.bins(b).split_us, session.frame_count
    names = [[latent_frame_name(i, k) for k in range(b + 1)] for i in range(frames)]
    lenses = []

    def reconstruct(session, b, label, calibration, folder, lens, progress):
        """COLMAP holding the given lens fixed: its model has the lens's values."""
        lenses.append(lens)
        (folder / "images").mkdir(parents=True, exist_ok=True)
        model = SparseModel(
            c2w={name: np.eye(4) for view in names for name in view},
            intrinsics=lens.intrinsics,
            distortion=np.asarray(lens.distortion),
            points=np.zeros((10, 3)),
            bounds=np.array([1.0, 3.0]),
        )
        outcome = Outcome(model, "exhaustive", True, ("exhaustive",))
        return estimate._Trial(label, calibration, folder, names, split_us, outcome)

    monkeypatch.setattr(estimate, "_reconstruct", reconstruct)
    first = Lens(64, 48, 50.0, 50.0, 31.5, 23.5, (-0.1, 0.01, 0.0, 0.0))
    estimate_poses(textureless_session, b=b, lens=first, force=True)
    estimate_poses(textureless_session, b=b, lens=first)  # the same lens: the poses stand
    assert lenses == [first]
    second = first.with_distortion((-0.2, 0.02))
    report = estimate_poses(textureless_session, b=b, lens=second)
    assert lenses == [first, second]
    assert "k1 -0.2, k2 +0.02" in report.summary()
    with Session.open(textureless_session) as session:
        assert np.allclose(session.poses(b).distortion, [-0.2, 0.02])
    other_size = Lens(346, 260, 280.0, 280.0, 172.5, 129.5)
    with pytest.raises(
        UsageError, match="calibration is for 346x260 images, the camera's are 64x48"
    ):
        estimate_poses(textureless_session, b=b, lens=other_size)
