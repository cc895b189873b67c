"""Inputs that break naive NeRF trainers: each must give finite losses and gradients."""

import numpy as np
import pytest
import torch

from seenerf.data.synthetic import plane_scene
from seenerf.model.config import FitConfig
from seenerf.train.methods import make_method
from seenerf.train.trainer import Trainer


def _check(scene, **overrides):
    config = FitConfig.of(steps=2, batch_pixels=16, warm_steps=0, validation_share=0.0, **overrides)
    trainer = Trainer(make_method(scene, config), log=lambda line: None)
    step = trainer.method.step(trainer.generator)
    loss, terms = step.loss(), step.shown()
    loss.backward()
    grads = [p.grad for p in trainer.model.parameters() if p.grad is not None]
    assert torch.isfinite(loss), terms
    assert grads and all(torch.isfinite(g).all() for g in grads)
    assert all(p.dtype == torch.float32 for p in trainer.model.parameters())
    summary = trainer.train()
    assert summary.skipped_steps == 0
    return trainer


def _scene(**kwargs):
    return plane_scene(height=8, width=10, frames=3, b=kwargs.pop("b", 2), test_views=1, **kwargs)


def test_saturated_pixels_at_one_and_zero():
    scene = _scene()
    scene.ldr[0] = 1.0
    scene.ldr[1] = 0.0
    _check(scene)


def test_radiance_near_zero_and_tiny_events():
    scene = _scene()
    scene.ldr[:] = 0.0
    scene.bins[:] = -40.0  # the scene goes dark fast: huge negative log changes
    _check(scene)


def test_exposures_one_ms_and_256_ms_in_one_scene():
    scene = _scene(exposure_s=np.array([0.001, 0.256, 0.016]))
    assert scene.exposure_s.min() == pytest.approx(0.001)
    _check(scene)
    _check(scene, variant="multi-exposure")


def test_a_bin_without_events_and_a_view_without_any():
    scene = _scene()
    scene.bins[0, 1] = 0.0
    scene.bins_raw[0, 1] = 0.0
    scene.bins[2] = 0.0
    scene.bins_raw[2] = 0.0
    _check(scene)


def test_no_events_at_all_in_the_session():
    scene = _scene()
    scene.bins[:] = 0.0
    scene.bins_raw[:] = 0.0
    trainer = _check(scene)
    assert trainer.method.frames.event_share == 0.0


@pytest.mark.parametrize("bins", [1, 8])
def test_one_and_eight_bins(bins):
    trainer = _check(_scene(b=bins))
    assert trainer.method.frames.sample(4, torch.Generator().manual_seed(0)).bins.shape == (4, bins)


def test_very_large_event_counts():
    scene = _scene()
    scene.bins *= 1e4
    scene.bins_raw *= 1e4
    _check(scene)


def test_rays_that_hit_nothing_render_the_background():
    scene = _scene()
    trainer = _check(scene)
    model = trainer.model
    origins = torch.tensor([[0.0, 0.0, -1000.0]])
    directions = torch.tensor([[0.0, 0.0, -1.0]])  # pointing away from the scene box
    log_radiance = model.render_log_radiance(origins, directions)
    assert torch.allclose(log_radiance, model.renderer.background.detach())
    hdr = model.hdr_from_log(log_radiance)
    assert torch.isfinite(hdr).all() and (hdr > 0).all()


@pytest.mark.parametrize("variant", ["point-crf-3d", "base", "oracle", "power-crf"])
def test_other_imaging_models_survive_saturation(variant):
    scene = _scene()
    scene.ldr[0] = 1.0
    scene.ldr[1] = 0.0
    _check(scene, variant=variant)


def _with_nan(step):
    from seenerf.train.methods import LossTerm, Step

    return Step([*step.terms, LossTerm("nan", 1.0, torch.tensor(float("nan")))], step.rays, 1)


def _wrap_steps(monkeypatch, trainer, change):
    """Each step of ``trainer`` as ``change`` makes it from the real one."""
    real_step = trainer.method.step
    monkeypatch.setattr(trainer.method, "step", lambda generator: change(real_step(generator)))


def test_a_fit_whose_every_loss_is_nan_fails_instead_of_reporting_success(monkeypatch):
    from seenerf.errors import TrainingDataError
    from seenerf.train.trainer import SKIPPED_IN_A_ROW_LIMIT

    config = FitConfig.of(steps=200, batch_pixels=16, warm_steps=0, validation_share=0.0)
    trainer = Trainer(make_method(_scene(), config), log=lambda line: None)
    calls = []

    def sometimes_nan(step):
        calls.append(1)
        # Steps 1-10 finite, then NaN for ever: the limit counts from step 11.
        return step if len(calls) <= 10 else _with_nan(step)

    _wrap_steps(monkeypatch, trainer, sometimes_nan)
    with pytest.raises(TrainingDataError, match=f"not finite in {SKIPPED_IN_A_ROW_LIMIT} steps"):
        trainer.train()
    assert trainer.summary.steps == 10 + SKIPPED_IN_A_ROW_LIMIT
    assert trainer.summary.skipped_steps == SKIPPED_IN_A_ROW_LIMIT


def test_isolated_nan_steps_are_skipped_and_counted(monkeypatch):
    config = FitConfig.of(steps=30, batch_pixels=16, warm_steps=0, validation_share=0.0)
    trainer = Trainer(make_method(_scene(), config), log=lambda line: None)
    calls = []

    def every_third_nan(step):
        calls.append(1)
        return _with_nan(step) if len(calls) % 3 == 0 else step

    _wrap_steps(monkeypatch, trainer, every_third_nan)
    summary = trainer.train()
    assert summary.steps == 30 and summary.skipped_steps == 10
