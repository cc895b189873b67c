"""The camera is a black box: no emulator fact reaches the pipeline, and mono stays mono.

One small monochrome emulated session is recorded twice over: as recorded (with ``truth/``),
and as a real camera would leave it (no ``truth/``, nothing about its source in
``session.json``). Calibration, poses, the resolved fit and its first losses must not tell them
apart.
"""

import json
import shutil

import cv2
import numpy as np
import OpenEXR
import pytest
import torch

from davis_io.emulator import EmulatedCamera
from davis_io.prepare import prepare_session
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.types import ColorFilter
from seenerf.data.session import load_training_data
from seenerf.model.config import FitConfig
from seenerf.train import fit_session, render_run
from seenerf.train.fit import resolved_settings
from seenerf.train.methods import make_method
from seenerf.train.trainer import Trainer

SMALL = dict(frames=4, test_views=1, baseline_m=0.18, width=173, height=130, focal_px=140.0)


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    root = tmp_path_factory.mktemp("blind")
    camera = EmulatedCamera("room", color_filter=ColorFilter.MONO, seed=3, **SMALL)
    record(camera, root / "emulated", bins=4)
    camera.write_truth(root / "emulated")
    shutil.copytree(root / "emulated", root / "camera")
    shutil.rmtree(root / "camera" / "truth")
    manifest_path = root / "camera" / "session.json"
    manifest = json.loads(manifest_path.read_text())
    manifest.update(source="usb", serial="00000001", device_config={})
    manifest_path.write_text(json.dumps(manifest))
    for name in ("emulated", "camera"):
        prepare_session(root / name, 4, log=lambda line: None)
    return root / "emulated", root / "camera"


def test_session_json_of_an_emulated_recording_states_no_sensor_value(twins):
    emulated, _ = twins
    text = (emulated / "session.json").read_text()
    for fact in ("threshold", "response", "dvs", "refractory", "cutoff", "noisy", "reinhard"):
        assert fact not in text


def test_calibration_and_poses_are_the_same_without_the_emulators_facts(twins):
    with Session.open(twins[0]) as emulated, Session.open(twins[1]) as camera:
        assert camera.truth() is None and emulated.truth() is not None
        measured, blind = emulated.calibration(), camera.calibration()
        assert measured.facts() == blind.facts()
        for field in ("pixel_factor_on", "pixel_factor_off", "response_log_exposure"):
            assert np.array_equal(getattr(measured, field), getattr(blind, field))
        poses, blind_poses = emulated.poses(4), camera.poses(4)
        assert poses.registered.all()
        assert np.array_equal(poses.c2w, blind_poses.c2w)
        assert np.array_equal(poses.intrinsics, blind_poses.intrinsics)


def test_the_resolved_fit_and_its_first_losses_are_the_same(twins):
    config = FitConfig.of(steps=3, seed=5, threads=1, warm_steps=20)
    losses, settings = [], []
    for folder in twins:
        data = load_training_data(folder, 4)
        trainer = Trainer(make_method(data, config), log=lambda line: None)
        settings.append(json.dumps(resolved_settings(trainer.method), default=str))
        steps = []
        for _ in range(3):
            torch.manual_seed(0)
            trainer._step()
            trainer.summary.steps += 1
            steps.append(trainer.last_terms)
        losses.append(steps)
    assert settings[0] == settings[1]
    assert losses[0] == losses[1]
    assert losses[0][0]["events"] > 0  # the events take part


def _channels(path):
    with OpenEXR.File(str(path)) as exr:
        return sorted(exr.channels())


@pytest.fixture(scope="module")
def camera_run(twins):
    """A short fit of the session as a real camera leaves it (no truth)."""
    _, camera = twins
    return fit_session(camera, FitConfig.of(steps=2, warm_steps=10), log=lambda line: None)


def test_a_mono_session_without_truth_renders_mono_everywhere(camera_run):
    result = camera_run
    renders = result.run_dir / "renders"
    exrs, pngs = sorted(renders.rglob("*.exr")), sorted(renders.rglob("*.png"))
    assert exrs and pngs
    assert all(_channels(path) == ["Y"] for path in exrs)
    assert all(cv2.imread(str(path), cv2.IMREAD_UNCHANGED).ndim == 2 for path in pngs)
    movie = result.run_dir / "orbit.mp4"
    orbit = render_run(result.run_dir, exposures_s=(0.1,), path="orbit", video=movie)
    assert all(_channels(path) == ["Y"] for path in orbit.rglob("*.exr"))
    capture = cv2.VideoCapture(str(movie))
    frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    readable, first = capture.read()
    # The 60 views of the orbit; 173 columns padded to 174 (MPEG-4 codes even sizes).
    assert readable and frames == len(list((orbit / "renders" / "hdr").glob("*.exr"))) == 60
    assert first.shape == (130, 174, 3)
    grey = [cv2.imread(str(p), cv2.IMREAD_UNCHANGED).ndim for p in orbit.rglob("*.png")]
    assert grey and set(grey) == {2}
    assert "hdr" not in result.metrics  # nothing to score without truth: renders only


def test_nerfstudio_export_reads_back_in_its_own_conventions(twins, tmp_path):
    from davis_io.poses.nerfstudio import export_nerfstudio

    _, camera = twins
    path = export_nerfstudio(camera, tmp_path / "ns")
    payload = json.loads(path.read_text())
    for key in ("camera_model", "fl_x", "fl_y", "cx", "cy", "w", "h", "k1", "k2", "p1", "p2"):
        assert key in payload
    assert payload["camera_model"] == "OPENCV" and (payload["w"], payload["h"]) == (173, 130)
    with Session.open(camera) as session:
        poses = session.poses(4)
    assert len(payload["frames"]) == int(poses.registered.sum())
    fx, fy, cx, cy = poses.intrinsics
    point = np.array([0.3, -0.2, 4.0, 1.0])  # in front of the first camera, in its frame
    first = payload["frames"][0]
    frame, index = (int(p) for p in first["file_path"][len("images/") : -len(".png")].split("_"))
    world = poses.c2w[frame, index] @ point
    # nerfstudio: OpenGL camera axes (y up, z backward), pixel i's centre at i + 0.5.
    camera_gl = np.linalg.inv(np.array(first["transform_matrix"])) @ world
    u = payload["fl_x"] * camera_gl[0] / -camera_gl[2] + payload["cx"] - 0.5
    v = payload["fl_y"] * -camera_gl[1] / -camera_gl[2] + payload["cy"] - 0.5
    # The session: OpenCV axes, pixel centres at integers.
    assert (u, v) == pytest.approx((fx * 0.3 / 4.0 + cx, fy * -0.2 / 4.0 + cy))
    image = cv2.imread(str(path.parent / first["file_path"]), cv2.IMREAD_UNCHANGED)
    assert image.shape == (130, 173)  # monochrome latent frames stay grey
    # COLMAP's points, as nerfstudio's methods that start from them read them.
    assert payload["ply_file_path"] == "sparse_pc.ply"
    ply = (path.parent / "sparse_pc.ply").read_text().splitlines()
    count = int(next(line for line in ply if line.startswith("element vertex")).split()[-1])
    rows = ply[ply.index("end_header") + 1 :]
    assert count == len(rows) > 100
    points = np.array([[float(word) for word in row.split()[:3]] for row in rows])
    depth = (np.linalg.inv(poses.c2w[frame, index]) @ np.c_[points, np.ones(count)].T)[2]
    assert np.median(depth) > 0  # the scene lies in front of the camera that saw it


def _exr_pixels(path):
    with OpenEXR.File(str(path)) as exr:
        return {name: channel.pixels.copy() for name, channel in exr.channels().items()}


def test_a_saved_run_renders_and_scores_in_a_new_process_as_the_fit_did(twins):
    import os
    import subprocess
    import sys

    emulated, _ = twins
    # One thread everywhere: several sum a ray's samples in an order that varies from run to
    # run (differences of 1e-6), which would hide nothing the saved state itself changes.
    result = fit_session(
        emulated,
        FitConfig.of(steps=3, warm_steps=10, threads=1, register_test_views=False),
        run_name="saved",
        log=lambda line: None,
    )
    run = result.run_dir
    fitted_hdr = {p.name: _exr_pixels(p) for p in (run / "renders" / "hdr").glob("*.exr")}
    fitted_ldr = {
        p.relative_to(run): cv2.imread(str(p), -1) for p in (run / "renders" / "ldr").rglob("*.png")
    }
    seecap = [sys.executable, "-c", "import sys; from davis_io.cli import main; sys.exit(main())"]
    one_thread = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    subprocess.run([*seecap, "render", str(run)], check=True, env=one_thread)
    subprocess.run([*seecap, "eval", str(run)], check=True, capture_output=True, env=one_thread)
    assert fitted_hdr
    for name, channels in fitted_hdr.items():
        again = _exr_pixels(run / "held-out" / "renders" / "hdr" / name)
        for channel, pixels in channels.items():
            assert np.array_equal(pixels, again[channel]), (name, channel)
    assert fitted_ldr
    for name, pixels in fitted_ldr.items():
        assert np.array_equal(pixels, cv2.imread(str(run / "held-out" / name), -1)), name
    scored = json.loads((run / "metrics.json").read_text())
    assert scored["hdr"] == result.metrics["hdr"]
    assert scored["ldr"] == result.metrics["ldr"]


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium here: `make browser` installs Debian's")
def test_the_report_opens_in_a_browser_with_every_image_and_a_working_slider(camera_run, tmp_path):
    import re
    import subprocess

    report = camera_run.run_dir / "report.html"
    assert report.exists()  # every fit writes one

    def body(url: str) -> dict:
        dom = subprocess.run(
            [
                CHROMIUM,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={tmp_path / 'profile'}",
                "--virtual-time-budget=10000",
                "--dump-dom",
                url,
            ],
            capture_output=True,
            text=True,
            timeout=120,
        ).stdout
        tag = re.search(r"<body([^>]*)>", dom).group(1)
        return dict(re.findall(r'data-([\w-]+)="([^"]*)"', tag))

    opened = body(report.as_uri())
    total = int(opened["images-total"])
    # Inputs, LDR and HDR renders of every view shown, and the three figures.
    assert total >= 3 * 1 + 3 and int(opened["images-loaded"]) == total
    saved = json.loads((camera_run.run_dir / "config.json").read_text())
    exposures = sorted(float(p.name) for p in (camera_run.run_dir / "renders" / "ldr").iterdir())
    assert float(opened["exposure"]) == pytest.approx(exposures[len(exposures) // 2])
    slid = body(report.as_uri() + "#exposure=0")  # the slider moved to the shortest exposure
    assert float(slid["exposure"]) == pytest.approx(exposures[0])
    assert saved["software"]["device"] == "cpu"
