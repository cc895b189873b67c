"""NDC of forward-facing scenes: hand-computed coordinates, round trips, when it applies."""

import math

import numpy as np
import pytest
import torch

from seenerf.render.frustum import forward_facing_space, frustum_box
from seenerf.render.rays import camera_rays

INTRINSICS = np.array([100.0, 100.0, 49.5, 39.5])
IMAGE = (80, 100)
BOUNDS = np.array([2.0, 10.0])


def _pose(yaw_deg: float = 0.0, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    yaw = math.radians(yaw_deg)
    pose = np.eye(4)
    pose[:3, :3] = [
        [math.cos(yaw), 0, math.sin(yaw)],
        [0, 1, 0],
        [-math.sin(yaw), 0, math.cos(yaw)],
    ]
    pose[:3, 3] = centre
    return pose


def test_ndc_of_a_ray_by_hand():
    space = forward_facing_space(np.stack([_pose()]), INTRINSICS, BOUNDS, IMAGE)
    assert space.near == pytest.approx(1.6)  # 0.8 x the near bound
    origin = torch.tensor([[0.5, -0.25, 0.0]])
    direction = torch.tensor([[0.1, 0.2, 1.0]])
    ndc_origin, ndc_direction = space.rays(origin, direction)
    # The ray meets the near plane z = 1.6 at (0.66, 0.07); x' = 2 fx / W * x / z, etc.
    expected_origin = [2.0 * 0.66 / 1.6, 2.5 * 0.07 / 1.6, -1.0]
    expected_end = [2.0 * 0.1, 2.5 * 0.2, 1.0]  # at infinity: the direction's image position
    np.testing.assert_allclose(ndc_origin[0].numpy(), expected_origin, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(
        (ndc_origin + ndc_direction)[0].numpy(), expected_end, rtol=1e-5, atol=1e-6
    )


def test_points_of_an_ndc_ray_lie_on_the_world_ray():
    poses = np.stack([_pose(5.0, (0.1, 0.0, -0.2)), _pose(-5.0, (-0.1, 0.05, 0.1))])
    space = forward_facing_space(poses, INTRINSICS, BOUNDS, IMAGE)
    origins, directions = camera_rays(
        torch.as_tensor(poses[0], dtype=torch.float32),
        torch.as_tensor(INTRINSICS, dtype=torch.float32),
        torch.tensor([0.0, 60.0, 99.0]),
        torch.tensor([0.0, 30.0, 79.0]),
    )
    ndc_origins, ndc_directions = space.rays(origins, directions)
    depths = []
    for t in (0.0, 0.5, 0.9):
        world = space.to_world(ndc_origins + t * ndc_directions)
        offset = world - origins
        assert torch.linalg.cross(offset, directions).norm(dim=-1).max() < 1e-4
        depths.append((offset * directions).sum(-1) / (directions * directions).sum(-1))
    assert (depths[1] > depths[0]).all() and (depths[2] > depths[1]).all()
    # z' is linear in disparity: halfway in t' is halfway between 1 / near and 0.
    reference_depth = space.to_world(ndc_origins + 0.5 * ndc_directions)
    w2c = torch.tensor(space.w2c)
    z = (reference_depth @ w2c[:, :3].T + w2c[:, 3])[:, 2]
    np.testing.assert_allclose(z.numpy(), 2 * space.near, rtol=1e-4)


def test_cameras_turned_far_apart_are_not_forward_facing():
    assert forward_facing_space(np.stack([_pose(0), _pose(60)]), INTRINSICS, BOUNDS, IMAGE) is None
    assert forward_facing_space(np.stack([_pose(0), _pose(20)]), INTRINSICS, BOUNDS, IMAGE)


def test_a_camera_far_in_front_of_the_others_is_not_forward_facing():
    poses = np.stack([_pose(), _pose(centre=(0.0, 0.0, 3.0))])
    assert forward_facing_space(poses, INTRINSICS, BOUNDS, IMAGE) is None


def test_the_box_holds_every_view_between_near_and_far():
    poses = np.stack([_pose(8.0, (0.2, 0.0, 0.0)), _pose(-8.0, (-0.2, 0.1, 0.0))])
    space = forward_facing_space(poses, INTRINSICS, BOUNDS, IMAGE)
    box = frustum_box(space, poses, INTRINSICS, BOUNDS, IMAGE)
    u, v = np.meshgrid(np.linspace(0, 99, 7), np.linspace(0, 79, 5))
    for pose in poses:
        local = np.stack([(u.ravel() - 49.5) / 100, (v.ravel() - 39.5) / 100, np.ones(u.size)], 1)
        for depth in (2.0, 5.0, 10.0):
            points = space.to_ndc(pose[:3, 3] + depth * local @ pose[:3, :3].T)
            assert (points >= np.array(box.low)).all() and (points <= np.array(box.high)).all()


def test_a_ray_going_backwards_misses_every_box():
    from seenerf.render.rays import SceneBox, intersect_box

    space = forward_facing_space(np.stack([_pose()]), INTRINSICS, BOUNDS, IMAGE)
    origins, directions = space.rays(torch.tensor([[0.0, 0.0, -5.0]]), torch.tensor([[0, 0, -1.0]]))
    entry, exit_ = intersect_box(origins, directions, SceneBox((-3.0,) * 3, (3.0,) * 3), 0.0, 1.0)
    assert torch.isfinite(origins).all() and float(exit_ - entry) == 0.0
