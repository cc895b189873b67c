import json

import numpy as np
import pytest

from davis_io.geometry import OPENCV_TO_OPENGL, nerfstudio_transforms
from seenerf.errors import CheckpointError
from seenerf.train.runs import open_run, orbit_poses, read_path


def test_orbit_circles_the_training_cameras(tiny_scene):
    poses = orbit_poses(tiny_scene, count=12)
    centres = tiny_scene.c2w[:, 0, :3, 3]
    distances = np.linalg.norm(poses[:, :3, 3] - centres.mean(axis=0), axis=1)
    assert poses.shape == (12, 4, 4)
    assert np.allclose(distances, distances[0], rtol=1e-4) and distances[0] > 0
    assert np.allclose(poses[0, :3, :3] @ poses[0, :3, :3].T, np.eye(3), atol=1e-5)


def test_transforms_json_round_trips_as_a_camera_path(tmp_path):
    c2w = np.tile(np.eye(4), (2, 1, 1))
    c2w[1, :3, 3] = [1.0, 2.0, 3.0]
    payload = nerfstudio_transforms(
        c2w, np.array([10.0, 10.0, 4.0, 3.0]), np.zeros(0), (6, 8), ["a.png", "b.png"]
    )
    # OpenGL axes flip y and z of the camera
    assert payload["frames"][0]["transform_matrix"][1][1] == -1.0
    path = tmp_path / "transforms.json"
    path.write_text(json.dumps(payload))
    assert np.allclose(read_path(path), c2w)
    assert np.allclose(OPENCV_TO_OPENGL @ OPENCV_TO_OPENGL, np.eye(4))


def test_bad_camera_path_and_missing_run_are_typed_errors(tmp_path):
    np.save(tmp_path / "path.npy", np.zeros((3, 3)))
    with pytest.raises(CheckpointError, match=r"\(N, 4, 4\)"):
        read_path(tmp_path / "path.npy")
    with pytest.raises(CheckpointError, match="seecap fit first"):
        open_run(tmp_path)


def test_a_video_shows_one_exposure_or_hdr_under_one_tone_map(tmp_path):
    from seenerf.eval.video import video_frames
    from seenerf.eval.views import RenderedViews
    from seenerf.train.runs import render_run

    with pytest.raises(CheckpointError, match="a video shows one exposure"):
        render_run(tmp_path, (0.01, 0.1), "orbit", None, tmp_path / "v.mp4")
    dim, bright = np.full((2, 2, 3), 0.5), np.full((2, 2, 3), 2.0)
    views = RenderedViews(
        np.zeros((2, 4, 4)), (0.01, 0.1), [dim, bright], [[dim, dim], [bright, bright]]
    )
    hdr = video_frames(views, None)
    # One peak (2.0) for the whole path: the dim view stays dimmer than the bright one.
    assert hdr[0][0, 0, 0] == pytest.approx(np.log1p(5000 * 0.25) / np.log(5001))
    assert hdr[1][0, 0, 0] == pytest.approx(1.0)
    assert video_frames(views, 0.09)[0] is bright  # the exposure nearest 0.09 s: 0.1 s
