"""Sub-frames of the exposure integral: hand-computed times, weights, poses and image motion."""

import numpy as np
import pytest
import torch

from davis_io.bins import trapezoid_weights
from davis_io.geometry import rotation_error_deg
from seenerf.data.batching import FrameSampler
from seenerf.data.subframes import (
    latent_fractions,
    latent_travel_px,
    median_travel_px,
    refine_exposure,
)
from seenerf.data.synthetic import plane_scene
from seenerf.errors import ConfigError
from seenerf.model.config import FitConfig
from seenerf.train.methods import make_method
from seenerf.train.trainer import Trainer

SPLIT_US = np.array([1000, 1010, 1030, 1060, 1100])
"""Latent times of one exposure: intervals of 10, 20, 30 and 40 µs in a 100 µs exposure."""


def _turn_z(degrees: float) -> np.ndarray:
    angle = np.radians(degrees)
    pose = np.eye(4)
    pose[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    return pose


def test_latent_fractions_are_recovered_from_the_trapezoid_weights():
    weights = trapezoid_weights(SPLIT_US)
    np.testing.assert_allclose(
        latent_fractions(weights[None])[0], [0.0, 0.1, 0.3, 0.6, 1.0], atol=1e-12
    )


def test_even_weights_of_a_zero_length_window_give_even_fractions():
    np.testing.assert_allclose(
        latent_fractions(np.full((1, 3), 1 / 3))[0], [0.0, 0.5, 1.0], atol=1e-12
    )


def test_two_subframes_halve_each_bin_and_keep_the_latent_poses():
    c2w = np.tile(np.eye(4), (1, 5, 1, 1))
    c2w[0, :, 0, 3] = [0.0, 1.0, 3.0, 6.0, 10.0]
    c2w[0, 1, :3, :3] = _turn_z(90.0)[:3, :3]
    weights = trapezoid_weights(SPLIT_US)[None]

    fine_c2w, fine_weights = refine_exposure(c2w, weights, 2)

    # Points at 0, 5, 10, 20, 30, 45, 60, 80, 100 µs: trapezoid weights by hand.
    expected = np.array([5, 10, 15, 20, 25, 30, 35, 40, 20]) / 200
    np.testing.assert_allclose(fine_weights[0], expected, atol=1e-9)
    np.testing.assert_array_equal(fine_c2w[0, ::2], c2w[0])
    np.testing.assert_allclose(fine_c2w[0, 1, :3, 3], [0.5, 0, 0], atol=1e-9)
    np.testing.assert_allclose(fine_c2w[0, 5, :3, 3], [4.5, 0, 0], atol=1e-9)
    # Half way between no turn and 90 degrees about z: 45 degrees each way.
    turned = rotation_error_deg(fine_c2w[0, 1:2, :3, :3], np.eye(3)[None])
    np.testing.assert_allclose(turned, [45.0], atol=1e-6)


def test_an_empty_bin_keeps_its_latent_pose_and_gets_no_weight():
    c2w = np.tile(np.eye(4), (1, 3, 1, 1))
    c2w[0, :, 0, 3] = [0.0, 1.0, 2.0]
    weights = trapezoid_weights(np.array([0, 0, 100]))[None]  # bin 0 lasts no time
    fine_c2w, fine_weights = refine_exposure(c2w, weights, 2)
    np.testing.assert_allclose(fine_weights[0], [0, 0, 0.25, 0.5, 0.25], atol=1e-9)
    np.testing.assert_allclose(fine_c2w[0, :, 0, 3], [0.0, 0.5, 1.0, 1.5, 2.0], atol=1e-9)


def test_one_subframe_returns_the_latent_poses():
    c2w, weights = np.tile(np.eye(4), (2, 3, 1, 1)), np.full((2, 3), 1 / 3)
    fine_c2w, fine_weights = refine_exposure(c2w, weights, 1)
    assert fine_c2w is c2w and fine_weights is weights


def test_travel_of_a_sideways_step_is_focal_times_step_over_depth():
    c2w = np.tile(np.eye(4), (2, 3, 1, 1))
    c2w[0, :, 0, 3] = [0.0, 0.1, 0.3]  # steps of 0.1 and 0.2 at depth 4: 5 and 10 px
    travel = latent_travel_px(c2w, np.array([200.0, 200.0, 16.0, 12.0]), 4.0, (24, 32))
    np.testing.assert_allclose(travel, [10.0, 0.0], atol=1e-9)


def test_median_travel_is_measured_at_the_harmonic_mean_depth():
    scene = plane_scene(height=24, width=32, frames=3, b=2, shake=0.3, test_views=1)
    scene.bounds = np.array([2.0, 6.0], np.float32)  # harmonic mean 3
    travel = latent_travel_px(scene.c2w, scene.intrinsics, 3.0, scene.image_size)
    assert median_travel_px(scene) == pytest.approx(np.median(travel))
    assert np.median(travel) > 0


def test_subframes_below_one_are_refused():
    with pytest.raises(
        ConfigError, match="--subframes 0 is out of range: give a whole number from 1"
    ):
        FitConfig.of(subframes=0)


def test_batches_with_subframes_hold_the_latent_rays_at_every_mth_pose():
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    frame, pixel = torch.tensor([0, 2, 1]), torch.tensor([5, 17, 79])
    latent = FrameSampler(scene, np.arange(3)).batch(frame, pixel)
    fine = FrameSampler(scene, np.arange(3), subframes=3).batch(frame, pixel)
    assert fine.origins.shape == (3, 7, 3) and fine.subframes == 3
    torch.testing.assert_close(fine.origins[:, ::3], latent.origins)
    torch.testing.assert_close(fine.directions[:, ::3], latent.directions)
    torch.testing.assert_close(fine.weights.sum(dim=1), torch.ones(3))


def test_a_fit_with_subframes_predicts_b_counts_and_trains():
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    config = FitConfig.of(steps=3, batch_pixels=16, warm_steps=0, validation_share=0.0, subframes=2)
    trainer = Trainer(make_method(scene, config), log=lambda line: None)
    batch = trainer.method.frames.sample(4, torch.Generator().manual_seed(0))
    assert batch.origins.shape[1] == 5
    assert trainer.model(batch)[-1].counts.shape == (4, 2)
    summary = trainer.train()
    assert summary.steps == 3 and summary.skipped_steps == 0
