"""Side-by-side scene views: panels by hand, and the files a benchmark run leaves."""

import json
import math
from types import SimpleNamespace

import cv2
import numpy as np
from benchlib import scene_images
from benchlib.scene_images import read_exr, scene_strip, write_scene_images

from seenerf.eval.export import write_exr

TONE = math.log(5001.0)


def test_strip_panels_are_truth_full_oracle_and_magnified_error():
    truth = np.array([[[1.0], [0.5]], [[0.25], [0.0]]], np.float32)
    full = truth * np.float32(0.5)
    strip = scene_strip(truth, full, None, error_gain=4.0)
    assert strip.shape == (2, 4 * 2 + 3 * 4, 1)
    np.testing.assert_allclose(strip[0, 0, 0], 1.0)  # the truth's peak maps to 1
    np.testing.assert_allclose(strip[0, 6, 0], math.log1p(2500.0) / TONE, rtol=1e-6)  # full
    np.testing.assert_allclose(strip[:, 12:14], 0.5)  # no oracle: grey
    error = 4 * (math.log1p(5000.0) - math.log1p(2500.0)) / TONE
    np.testing.assert_allclose(strip[0, 18, 0], min(error, 1.0), rtol=1e-6)
    np.testing.assert_allclose(strip[1, 19, 0], 0.0, atol=1e-7)  # black stays black
    np.testing.assert_allclose(strip[:, 2:6], 1.0)  # white gap
    same = scene_strip(truth, truth, truth)
    np.testing.assert_allclose(same[:, 12:14], same[:, :2])
    np.testing.assert_allclose(same[:, 18:], 0.0)


def test_a_run_folder_gives_its_scene_image_with_the_runs_scale(tmp_path, monkeypatch):
    session = tmp_path / "room"
    truth = np.linspace(0.01, 2.0, 6 * 8, dtype=np.float32).reshape(6, 8, 1)
    emulated = SimpleNamespace(test_hdr=truth[None])
    monkeypatch.setattr(scene_images, "load_truth", lambda folder: emulated)
    run = session / "fit" / "bench-fast-full"
    write_exr(run / "renders" / "hdr" / "000.exr", truth * 4, {})  # off by the scale below
    (run / "metrics.json").write_text(json.dumps({"hdr": {"scale": [0.25]}}))
    np.testing.assert_allclose(read_exr(run / "renders" / "hdr" / "000.exr"), truth * 4)

    written = write_scene_images({"room": session, "lamp": tmp_path / "lamp"}, "fast", tmp_path)

    assert written == ["room"]  # lamp has no run
    image = cv2.imread(str(tmp_path / "scenes" / "room.png"), cv2.IMREAD_UNCHANGED)
    assert image.shape == (6, 4 * 8 + 3 * 4)
    np.testing.assert_array_equal(image[:, :8], image[:, 12:20])  # full matches the truth
    assert (image[:, 36:] == 0).all()  # so its error is nothing
    assert (image[:, 24:32] == 128).all()  # and no oracle ran
