import math
from types import SimpleNamespace

import numpy as np
import pytest

from seenerf.eval.metrics import (
    align_channel_scale,
    align_global_scale,
    hdr_metrics,
    log_contrast,
    psnr,
    residual_blur,
    ssim,
    tone_map_pair,
)
from seenerf.eval.scores import score_views
from seenerf.eval.views import RenderedViews


def test_psnr_by_hand():
    # error 0.1 everywhere -> MSE 0.01 -> 10 log10(1 / 0.01) = 20 dB
    assert psnr(np.full((4, 4), 0.6), np.full((4, 4), 0.5)) == pytest.approx(20.0)
    assert psnr(np.ones(3), np.ones(3)) == math.inf


def test_ssim_of_constant_images_by_hand():
    # constant windows: variances and covariance vanish, SSIM = (2 ab + c1) / (a^2 + b^2 + c1)
    a, b, c1 = 0.5, 0.25, 0.01**2
    expected = (2 * a * b + c1) / (a * a + b * b + c1)
    assert ssim(np.full((16, 16), a), np.full((16, 16), b)) == pytest.approx(expected, rel=1e-9)
    image = np.random.default_rng(0).random((20, 24, 3))
    assert ssim(image, image) == pytest.approx(1.0)
    assert ssim(image, 1 - image) < 0


def test_tone_map_normalises_by_truth_maximum_and_clips_prediction():
    truth = np.array([0.0, 1.0, 2.0])
    pred = np.array([0.0, 4.0, 2.0])  # 4 / 2 = 2 clips to 1
    tp, tt = tone_map_pair(pred, truth)
    # truth 1 / max 2 = 0.5 -> ln(2501) / ln(5001)
    assert tt[1] == pytest.approx(math.log(2501) / math.log(5001))
    assert tp[1] == pytest.approx(1.0) and tt[2] == pytest.approx(1.0)


def test_channel_scale_alignment_recovers_white_balance():
    rng = np.random.default_rng(1)
    truth = rng.uniform(0.01, 100, (2, 8, 8, 3))
    pred = truth / np.array([2.0, 3.0, 0.5])
    assert align_channel_scale(pred, truth) == pytest.approx([2.0, 3.0, 0.5])
    aligned = hdr_metrics(list(pred), list(truth), align="channel")
    raw = hdr_metrics(list(pred), list(truth), align="none")
    assert aligned["psnr"] == math.inf or aligned["psnr"] > 100
    assert raw["psnr"] < 40
    # One global scale cannot undo a colour cast: the median ratio over all channels is 2.
    assert align_global_scale(pred, truth) == pytest.approx(2.0, rel=0.05)
    assert hdr_metrics(list(pred), list(truth), align="global")["psnr"] < aligned["psnr"]


def test_global_scale_recovers_a_grey_exposure_difference():
    rng = np.random.default_rng(2)
    truth = rng.uniform(0.01, 100, (2, 8, 8, 3))
    assert align_global_scale(truth / 7.0, truth) == pytest.approx(7.0)
    assert hdr_metrics(list(truth / 7.0), list(truth), align="global")["psnr"] > 100


def test_empty_view_lists_score_nan():
    assert math.isnan(hdr_metrics([], [], align="global")["psnr"])


def test_crf_error_is_zero_for_the_true_curve_and_grows_with_a_shift():
    from types import SimpleNamespace

    import torch

    from seenerf.data.synthetic import plane_scene, true_response
    from seenerf.eval.crf import crf_error
    from seenerf.eval.views import RenderedViews

    scene = plane_scene(height=8, width=10, frames=2, b=2, test_views=0)
    views = RenderedViews(np.zeros((0, 4, 4)), ())

    def model_with(offset):
        return SimpleNamespace(crf=lambda x: torch.as_tensor(true_response(x.numpy() + offset)))

    exact = crf_error(model_with(0.0), scene, views)
    assert max(exact["rms"]) < 2e-3  # only the interpolation between the 0.1-wide samples
    shifted = crf_error(model_with(0.5), scene, views)
    # By hand: the slope of (x / (x + 1)) ** (1 / 2.2) in ln x peaks at 0.184 (x / (x + 1) =
    # 0.3125), so a shift of 0.5 moves the curve by up to about 0.09.
    assert 0.04 < min(shifted["rms"]) and 0.08 < max(shifted["max"]) < 0.11
    assert crf_error(SimpleNamespace(crf=None), scene, views) is None


def test_crf_error_of_a_monochrome_sensor_compares_only_the_curve_it_uses():
    from types import SimpleNamespace

    import torch

    from davis_io.types import ColorFilter
    from seenerf.data.synthetic import plane_scene, true_response
    from seenerf.eval.crf import crf_error
    from seenerf.eval.views import RenderedViews

    scene = plane_scene(height=8, width=10, frames=2, b=2, test_views=0, color=ColorFilter.MONO)
    views = RenderedViews(np.zeros((0, 4, 4)), ())
    offsets = torch.tensor([0.0, 2.0, 2.0])  # the unused green and blue curves far off

    model = SimpleNamespace(crf=lambda x: torch.as_tensor(true_response((x + offsets).numpy())))
    error = crf_error(model, scene, views)
    assert error["channels"] == [0] and len(error["rms"]) == 1 and error["rms"][0] < 2e-3


def test_log_contrast_recovers_a_power_law_per_channel():
    truth = np.random.default_rng(0).uniform(0.01, 20.0, size=(2, 30, 40, 3))
    predicted = np.stack(
        [3.0 * truth[..., 0] ** 0.8, truth[..., 1], 0.5 * truth[..., 2] ** 1.25], -1
    )
    np.testing.assert_allclose(log_contrast(predicted, truth), [0.8, 1.0, 1.25], rtol=1e-9)


def test_residual_blur_finds_the_blur_of_a_render():
    import cv2

    rng = np.random.default_rng(0)
    truth = [rng.uniform(0.0, 1.0, size=(40, 50, 3)).astype(np.float32) for _ in range(2)]
    blurred = [cv2.GaussianBlur(t, (0, 0), 0.75) for t in truth]
    found = residual_blur(blurred, truth)
    assert found["sigma_px"] == 0.75 and found["psnr_gain"] > 10.0
    assert residual_blur(truth, truth) == {"sigma_px": 0.0, "psnr_gain": 0.0}
    # A monochrome view (H, W, 1) keeps its shape through the blur.
    grey = [t[..., :1] for t in truth]
    assert residual_blur([b[..., :1] for b in blurred], grey)["sigma_px"] == 0.75


def test_crf_plot_draws_only_the_curves_in_use(tmp_path):
    import cv2

    from seenerf.eval.plots import crf_plot

    x = np.linspace(-6.0, 4.0, 50)
    curve = 1.0 / (1.0 + np.exp(-x))
    learned = (x, np.stack([curve, curve**0.8, curve**1.2], axis=1))
    true = (x, curve[:, None])
    crf_plot(tmp_path / "mono.png", learned, true, channels=(0,))
    crf_plot(tmp_path / "rgb.png", learned, true)
    mono = cv2.imread(str(tmp_path / "mono.png")).astype(int)
    rgb = cv2.imread(str(tmp_path / "rgb.png")).astype(int)
    assert _coloured_pixels(mono) == 0 and _coloured_pixels(rgb) > 500


def test_training_curves_are_drawn_from_the_history(tmp_path):
    import cv2

    from seenerf.eval.plots import training_curves

    history = [
        {"step": s, "val_psnr": 20 + s / 100, "ldr": 1 / s, "events": 2 / s} for s in (1, 50, 100)
    ]
    training_curves(tmp_path / "training.png", history)
    image = cv2.imread(str(tmp_path / "training.png"))
    assert image is not None and image.shape[0] > 200 and _coloured_pixels(image) > 100
    training_curves(tmp_path / "empty.png", [])
    assert not (tmp_path / "empty.png").exists()


def _coloured_pixels(image):
    return int((image.max(-1) - image.min(-1) > 60).sum())


def test_a_psnr_only_score_has_the_full_scores_psnrs_and_no_ssim():
    rng = np.random.default_rng(5)
    exposures = (0.01, 0.04, 0.15, 0.6, 2.4)
    truth_hdr = rng.uniform(0.05, 4.0, (2, 24, 32, 3))
    truth_ldr = np.clip(truth_hdr[:, None] * np.asarray(exposures)[None, :, None, None, None], 0, 1)
    noisy = truth_hdr * rng.uniform(0.8, 1.2, truth_hdr.shape)
    views = RenderedViews(
        np.tile(np.eye(4), (2, 1, 1)),
        exposures,
        list(noisy),
        [list(np.clip(noisy * e, 0, 1)) for e in exposures],
    )
    data = SimpleNamespace(
        test=SimpleNamespace(hdr=truth_hdr, ldr=truth_ldr, exposures_s=exposures)
    )
    full, light = score_views(views, data), score_views(views, data, psnr_only=True)
    assert light["hdr"]["psnr"] == full["hdr"]["psnr"] and math.isnan(light["hdr"]["ssim"])
    # Novel exposures: the mean of the 2nd and 4th (0.04 s and 0.6 s).
    novel = (full["ldr"]["0.04"]["psnr"] + full["ldr"]["0.6"]["psnr"]) / 2
    assert light["novel_exposure"]["psnr"] == pytest.approx(novel) == full["novel_exposure"]["psnr"]
    assert 0 < full["hdr"]["ssim"] < 1 and "residual_blur" not in light


def test_renders_meet_the_truth_at_their_own_exposure_whatever_the_order():
    rng = np.random.default_rng(6)
    exposures = (0.01, 0.04, 0.15, 0.6, 2.4)
    truth_hdr = rng.uniform(0.05, 4.0, (2, 24, 32, 3))
    truth_ldr = np.clip(truth_hdr[:, None] * np.asarray(exposures)[None, :, None, None, None], 0, 1)
    data = SimpleNamespace(
        test=SimpleNamespace(hdr=truth_hdr, ldr=truth_ldr, exposures_s=exposures)
    )
    noisy = truth_hdr * rng.uniform(0.95, 1.05, truth_hdr.shape)

    def views_at(asked):
        ldr = [list(np.clip(noisy * e, 0, 1)) for e in asked]
        return RenderedViews(np.tile(np.eye(4), (2, 1, 1)), asked, list(noisy), ldr)

    ordered = score_views(views_at(exposures), data)
    shuffled = score_views(views_at((0.6, 0.01, 2.4, 0.15, 0.04)), data)
    for key, score in ordered["ldr"].items():
        assert shuffled["ldr"][key]["psnr"] == score["psnr"]
    assert shuffled["novel_exposure"] == ordered["novel_exposure"]
    assert shuffled["residual_blur"] == ordered["residual_blur"]
    # A near-perfect render: every exposure scores high once paired with its own truth.
    assert min(score["psnr"] for score in shuffled["ldr"].values()) > 25
    # An exposure the truth lacks is rendered but not scored; novel keeps what it has.
    partial = score_views(views_at((0.6, 0.3)), data)
    assert list(partial["ldr"]) == ["0.6"]
    assert partial["novel_exposure"]["psnr"] == ordered["ldr"]["0.6"]["psnr"]
    assert "residual_blur" not in partial
