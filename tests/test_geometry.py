import numpy as np
import pytest

from davis_io.errors import UsageError
from davis_io.geometry import (
    c2w_from_w2c,
    colmap_from_opencv_intrinsics,
    interpolate_poses,
    opencv_from_colmap_intrinsics,
    rotation_error_deg,
    umeyama,
)


def rz(degrees):
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def test_umeyama_recovers_a_hand_made_similarity():
    source = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    # target = 2 * Rz(90) * source + (1, 2, 3): (1,0,0) -> (0,2,0)*... i.e. (1, 4, 3)
    target = 2 * source @ rz(90).T + [1, 2, 3]
    assert np.allclose(target[1], [1, 4, 3])
    fit = umeyama(source, target)
    assert fit.scale == pytest.approx(2.0)
    assert np.allclose(fit.rotation, rz(90), atol=1e-12)
    assert np.allclose(fit.translation, [1, 2, 3])
    assert np.allclose(fit.inverse().apply_points(target), source)


def test_umeyama_never_returns_a_reflection():
    rng = np.random.default_rng(0)
    source = rng.standard_normal((10, 3))
    mirrored = source * [1, 1, -1]
    fit = umeyama(source, mirrored)
    assert np.linalg.det(fit.rotation) == pytest.approx(1.0)


def test_umeyama_rigid_keeps_scale_one():
    source = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    assert umeyama(source, 3 * source, with_scale=False).scale == 1.0


@pytest.mark.parametrize(
    "source, target",
    [
        (np.zeros((2, 3)), np.zeros((2, 3))),  # too few points
        (np.zeros((4, 3)), np.ones((4, 3))),  # source points coincide
        (np.zeros((4, 2)), np.zeros((4, 2))),  # not 3-D
    ],
)
def test_umeyama_rejects_bad_input(source, target):
    with pytest.raises(UsageError):
        umeyama(source, target)


def test_rotation_error_is_the_relative_angle():
    assert rotation_error_deg(np.eye(3), rz(30)) == pytest.approx(30.0)
    assert rotation_error_deg(rz(-10), rz(25)) == pytest.approx(35.0)


def test_c2w_from_w2c_by_hand():
    # Camera at (0, 0, 5) with identity rotation: x_cam = x_world + t, t = -(0, 0, 5).
    c2w = c2w_from_w2c(np.eye(3), [0, 0, -5])
    assert np.allclose(c2w[:3, 3], [0, 0, 5])
    rotation = rz(90)
    c2w = c2w_from_w2c(rotation, [1, 0, 0])
    assert np.allclose(c2w[:3, :3], rotation.T)
    assert np.allclose(rotation @ c2w[:3, 3] + [1, 0, 0], 0)  # the centre maps to the origin


def test_interpolation_slerps_rotation_and_lerps_centre():
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[1, :3, :3] = rz(90)
    poses[1, :3, 3] = [2, 0, 0]
    out = interpolate_poses([0, 100], poses, [50, -10, 200, 25])
    assert np.allclose(out[0, :3, :3], rz(45))
    assert np.allclose(out[0, :3, 3], [1, 0, 0])
    assert np.allclose(out[1], poses[0]) and np.allclose(out[2], poses[1])  # held outside
    assert rotation_error_deg(out[3, :3, :3], np.eye(3)) == pytest.approx(22.5)


def test_interpolation_edge_cases():
    pose = np.eye(4)[None]
    assert interpolate_poses([5], pose, [0, 9]).shape == (2, 4, 4)
    assert interpolate_poses([0, 1], np.tile(np.eye(4), (2, 1, 1)), []).shape == (0, 4, 4)
    with pytest.raises(UsageError):
        interpolate_poses([], np.zeros((0, 4, 4)), [1])
    with pytest.raises(UsageError):
        interpolate_poses([3, 3], np.tile(np.eye(4), (2, 1, 1)), [1])


def test_intrinsics_pixel_conventions():
    # COLMAP's top-left pixel centre is (0.5, 0.5), OpenCV's (0, 0).
    opencv = opencv_from_colmap_intrinsics([280, 280, 173, 130])
    assert np.allclose(opencv, [280, 280, 172.5, 129.5])
    assert np.allclose(colmap_from_opencv_intrinsics([1, 2, 3, 4]), [1, 2, 3.5, 4.5])


def test_align_poses_takes_its_rotation_from_the_orientations_not_the_centres():
    from scipy.spatial.transform import Rotation

    from davis_io.geometry import Similarity, align_poses

    rng = np.random.default_rng(4)
    true = np.tile(np.eye(4), (12, 1, 1))
    true[:, :3, :3] = Rotation.from_rotvec(rng.normal(0, 0.05, (12, 3))).as_matrix()
    true[:, :3, 3] = np.c_[rng.uniform(-0.2, 0.2, (12, 2)), np.zeros(12)]  # a hand-held plane
    known = Similarity(3.0, rz(30), np.array([1.0, -2.0, 0.5]))
    estimated = known.inverse().apply_poses(true)
    # The reconstruction tilts its plane of centres by half a degree about y, not the cameras.
    tilt = Rotation.from_rotvec([0, np.radians(0.5), 0]).as_matrix()
    estimated[:, :3, 3] = estimated[:, :3, 3] @ (known.rotation @ tilt @ known.rotation.T).T
    fit = align_poses(estimated, true)
    assert np.allclose(fit.rotation, known.rotation, atol=1e-9)  # orientations are exact
    assert fit.scale == pytest.approx(3.0, rel=1e-3)
    mapped = fit.apply_poses(estimated)
    # arccos near 1 turns rounding of 1e-16 into about 1e-6 degrees: exact is below 1e-4.
    assert np.allclose(rotation_error_deg(mapped[:, :3, :3], true[:, :3, :3]), 0, atol=1e-4)
    # A fit to the centres would have turned every camera by about the tilt.
    centres = umeyama(estimated[:, :3, 3], true[:, :3, 3])
    assert rotation_error_deg(centres.rotation, known.rotation) > 0.4
