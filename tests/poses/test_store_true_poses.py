import numpy as np

from davis_io.emulator import EmulatedCamera
from davis_io.geometry import rotation_error_deg
from davis_io.poses.truth import store_true_poses
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.session.truth import load_truth, save_truth


def test_stored_poses_are_the_truth_at_the_latent_times(tmp_path):
    camera = EmulatedCamera(frames=3, test_views=1, width=48, height=36, focal_px=40.0, seed=3)
    folder = tmp_path / "tiny"
    record(camera, folder, bins=2)
    save_truth(camera.truth, folder / "truth")

    store_true_poses(folder, 2)

    truth = load_truth(folder / "truth")
    with Session.open(folder) as session:
        poses, split_us = session.poses(2), session.bins(2).split_us
    assert split_us.shape == (3, 3) and poses.c2w.shape == (3, 3, 4, 4)
    assert poses.registered.all()
    expected = truth.c2w_at(split_us.reshape(-1))
    stored = poses.c2w.reshape(-1, 4, 4)
    # Neighbouring latent poses differ by over 1 degree and 3 mm (the shake), so a pose at the
    # wrong time fails; the two interpolations (of the 17 sub-frame poses per exposure, and of
    # the 1 ms path) agree to about 0.015 degree and 0.013 mm.
    assert rotation_error_deg(expected[1:, :3, :3], expected[:-1, :3, :3]).min() > 1.0
    assert np.linalg.norm(expected[1:, :3, 3] - expected[:-1, :3, 3], axis=1).min() > 3e-3
    assert rotation_error_deg(stored[:, :3, :3], expected[:, :3, :3]).max() < 0.05
    assert np.linalg.norm(stored[:, :3, 3] - expected[:, :3, 3], axis=1).max() < 1e-4
    np.testing.assert_allclose(poses.intrinsics, truth.intrinsics)
    near, far = truth.depth_range_m
    np.testing.assert_allclose(poses.bounds, [0.9 * near, 1.1 * far])
    assert poses.distortion.size == 0
