"""The training views' learned pose corrections: the rotation formula, how a correction applies,
that training moves it, and that a saved run keeps it."""

import cv2
import numpy as np
import pytest
import torch

from seenerf.model.config import FitConfig
from seenerf.model.pose_correction import PoseCorrection, rotation_matrices
from seenerf.train.builder import with_refined_poses
from seenerf.train.checkpoint import load_model_state
from seenerf.train.methods import make_method
from seenerf.train.trainer import Trainer


def test_rotations_are_rodrigues_and_smooth_at_zero():
    rng = np.random.default_rng(0)
    vectors = np.concatenate([rng.normal(size=(6, 3)), [[1e-7, 0, 0], [0, 0, 0]]])
    ours = rotation_matrices(torch.as_tensor(vectors)).numpy()
    for vector, rotation in zip(vectors, ours, strict=True):
        np.testing.assert_allclose(rotation, cv2.Rodrigues(vector)[0], atol=1e-12)
    at_zero = torch.zeros(1, 3, dtype=torch.float64, requires_grad=True)
    rotation_matrices(at_zero)[0, 1, 0].backward()  # d R_yx / d w_z = 1 at zero
    assert at_zero.grad.tolist() == [[0.0, 0.0, 1.0]]


def test_a_correction_turns_and_moves_each_view_in_its_own_camera_frame():
    correction = PoseCorrection(2)
    c2w = np.tile(np.eye(4, dtype=np.float32), (2, 3, 1, 1))
    c2w[1, :, :3, 3] = [1.0, 2.0, 3.0]
    np.testing.assert_array_equal(correction.apply(c2w), c2w)  # none at the start
    with torch.no_grad():
        correction.twist[1] = torch.tensor([0.0, 0.0, np.pi / 2, 0.5, 0.0, 0.0])
    moved = correction.apply(c2w)
    np.testing.assert_array_equal(moved[0], c2w[0])
    # 90 degrees about the camera's z, then half a unit along its x: world x stays x here.
    expected = np.array([[0, -1, 0, 1.5], [1, 0, 0, 2.0], [0, 0, 1, 3.0], [0, 0, 0, 1]])
    for pose in moved[1]:
        np.testing.assert_allclose(pose, expected, atol=1e-6)
    turned, shifted = correction.sizes()
    np.testing.assert_allclose(turned, [0.0, 90.0], atol=1e-5)
    np.testing.assert_allclose(shifted, [0.0, 0.5], atol=1e-7)
    assert float(correction.prior().detach()) == pytest.approx((np.pi**2 / 4 + 0.25) / 2, rel=1e-6)


def _config(**overrides):
    values = {"steps": 6, "batch_pixels": 6, "warm_steps": 2, "validation_share": 0.1}
    return FitConfig.of(**{**values, "threads": 1, "refine_poses": True, **overrides})


def test_training_refines_the_poses_and_a_saved_run_keeps_them(tiny_scene, tmp_path):
    trainer = Trainer(make_method(tiny_scene, _config()), run_dir=tmp_path, log=lambda line: None)
    trainer.train()
    twist = trainer.model.pose_correction.twist.detach()
    assert torch.count_nonzero(twist) == twist.numel()  # every view's every component moved
    assert "poses" in trainer.last_terms
    refined = with_refined_poses(tiny_scene, trainer.model)
    assert not np.allclose(refined.c2w, tiny_scene.c2w)
    model = make_method(tiny_scene, _config()).model
    load_model_state(tmp_path / "checkpoint.pt", model)
    np.testing.assert_array_equal(with_refined_poses(tiny_scene, model).c2w, refined.c2w)


def test_without_refinement_or_for_the_oracle_the_poses_are_as_given(tiny_scene):
    plain = make_method(tiny_scene, _config(refine_poses=False)).model
    assert plain.pose_correction is None and with_refined_poses(tiny_scene, plain) is tiny_scene
    oracle = make_method(tiny_scene, _config(variant="oracle")).model
    assert oracle.pose_correction is None  # trained at the true poses
