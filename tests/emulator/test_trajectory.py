import numpy as np
import pytest

from davis_io.emulator.trajectory import (
    Shake,
    Trajectory,
    grid_positions,
    look_at,
    rotation_from_vector,
)


def test_look_at_straight_ahead_is_identity():
    pose = look_at(np.zeros((1, 3)), np.array([0.0, 0.0, 5.0]))[0]
    np.testing.assert_allclose(pose, np.eye(4), atol=1e-12)


def test_rotation_from_vector_quarter_turn_about_z():
    rotation = rotation_from_vector(np.array([[0.0, 0.0, np.pi / 2]]))[0]
    np.testing.assert_allclose(rotation @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-12)


def test_grid_positions_serpentine_and_offset():
    # 4 views: 2 columns; the second row runs right to left, so view 1 and 2 are neighbours.
    positions = grid_positions(4, np.zeros(3), 1.0, offset=False)
    np.testing.assert_allclose(positions[:, 0], [-0.5, 0.5, 0.5, -0.5])
    np.testing.assert_allclose(positions[:, 1], [-0.3, -0.3, 0.3, 0.3])
    shifted = grid_positions(4, np.zeros(3), 1.0, offset=True)
    np.testing.assert_allclose(shifted - positions, [[0.5, 0.3, 0]] * 4)
    assert grid_positions(0, np.zeros(3), 1.0, offset=False).shape == (0, 3)


def test_shake_has_the_configured_rms_rotation():
    # Each axis is a sum of sinusoids normalised to the requested RMS (roll gets half).
    shake = Shake(rotation_deg=1.0, translation_m=0.0, seed=3)
    times = np.arange(0, 60_000_000, 2000)
    offsets = shake.offsets(times)
    pitch = np.rad2deg(np.arcsin(offsets[:, 2, 1]))  # small angles: R[2,1] ~ rotation about x
    assert np.sqrt(np.mean(pitch**2)) == pytest.approx(1.0, rel=0.1)
    np.testing.assert_allclose(offsets[:, :3, 3], 0)


def test_trajectory_rests_during_exposures_and_moves_smoothly_between():
    positions = np.array([[0.0, 0, 0], [0.1, 0, 0]])
    windows = np.array([[0, 100_000], [150_000, 250_000]])
    path = Trajectory(positions, np.array([0.0, 0, 4]), windows, Shake(0.0, 0.0, 0))
    np.testing.assert_allclose(path.base_positions(np.array([0, 100_000])), positions[[0, 0]])
    np.testing.assert_allclose(path.base_positions(np.array([150_000, 300_000])), positions[[1, 1]])
    # Minimum jerk: half way in time is half way in space.
    assert path.base_positions(np.array([125_000]))[0, 0] == pytest.approx(0.05)
    poses = Trajectory(positions, np.array([0.0, 0, 4]), windows, Shake(1.0, 0.002, 1)).c2w(
        np.arange(0, 250_001, 1000)
    )
    rotations = poses[:, :3, :3]
    np.testing.assert_allclose(
        rotations @ rotations.transpose(0, 2, 1), np.tile(np.eye(3), (251, 1, 1)), atol=1e-9
    )
    # Smooth: successive 1 ms poses differ by well under 0.1 degree.
    relative = np.einsum("nji,njk->nik", rotations[:-1], rotations[1:])
    angles = np.rad2deg(np.arccos(np.clip((np.trace(relative, axis1=1, axis2=2) - 1) / 2, -1, 1)))
    assert angles.max() < 0.1


def project(c2w, point, focal):
    """Pixel offsets from the image centre of a world point seen from poses ``(N, 4, 4)``."""
    camera = np.einsum("nji,nj->ni", c2w[:, :3, :3], point - c2w[:, :3, 3])
    return focal * camera[:, :2] / camera[:, 2:]


def test_default_shake_blurs_by_pixels_and_moves_under_a_pixel_per_dvs_step():
    from davis_io.emulator import EmulatedCamera

    camera = EmulatedCamera("room")
    config = camera.config
    target = np.asarray(camera.scene.target)
    extents, steps = [], []
    for start, end in config.frame_windows()[:, 1:3]:
        path = project(camera.trajectory.c2w(np.arange(start, end + 1, 1000)), target, 280.0)
        extents.append(np.linalg.norm(path - path.mean(axis=0), axis=1).max() * 2)
    # Blur: the point sweeps several to tens of pixels during each 150 ms exposure.
    assert 4 < np.median(extents) < 40
    # Whole recording, in DVS steps: at most one pixel of motion per step.
    times = np.arange(0, config.end_us, config.dvs_step_us)
    path = project(camera.trajectory.c2w(times), target, 280.0)
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() < 1.0


def test_imu_at_rest_reads_one_g_up_and_no_rotation():
    from davis_io.emulator.trajectory import imu_readings

    still = Trajectory(
        np.zeros((1, 3)), np.array([0.0, 0, 4]), np.array([[0, 10_000]]), Shake(0.0, 0.0, 0)
    )
    samples = imu_readings(still, np.arange(0, 5000, 1000))
    # Level camera (y down): the specific force points up, -y, 1 g.
    np.testing.assert_allclose(samples["acc_g"], [[0, -1, 0]] * 5, atol=1e-9)
    np.testing.assert_allclose(samples["gyro_dps"], 0, atol=1e-9)
    assert len(imu_readings(still, np.empty(0, np.int64))) == 0


def test_imu_gyro_integrates_to_the_rotation_between_poses():
    from davis_io.emulator.trajectory import imu_readings

    shaky = Trajectory(
        np.zeros((1, 3)), np.array([0.0, 0, 4]), np.array([[0, 10**6]]), Shake(1.0, 0.0, 4)
    )
    times = np.arange(100_000, 120_001, 100)
    rate = np.deg2rad(imu_readings(shaky, times)["gyro_dps"])
    integral = ((rate[1:] + rate[:-1]) / 2 * 1e-4).sum(axis=0)
    first, last = shaky.c2w(times[[0, -1]])[:, :3, :3]
    relative = first.T @ last
    angle = np.arccos((np.trace(relative) - 1) / 2)
    rotvec = (
        angle
        / (2 * np.sin(angle))
        * np.array(
            [
                relative[2, 1] - relative[1, 2],
                relative[0, 2] - relative[2, 0],
                relative[1, 0] - relative[0, 1],
            ]
        )
    )
    np.testing.assert_allclose(integral, rotvec, rtol=0.02, atol=1e-6)
