import cv2
import numpy as np
import pytest

from davis_io.colorfilter import filter_channels, filter_weights
from davis_io.emulator.colorfilter import through_filter
from davis_io.emulator.raytrace import PinholeCamera, Quad, Sphere, box_faces, nearest_hits
from davis_io.emulator.scenes import SCENES, get_scene
from davis_io.emulator.trajectory import look_at
from davis_io.errors import UsageError
from davis_io.types import ColorFilter

DAVIS = PinholeCamera(346, 260, 280.0, 280.0, 172.5, 129.5)


def front_view(scene):
    return look_at(np.array([scene.camera_center]), np.array(scene.target))[0]


def test_quad_facing_the_camera_has_its_distance_as_depth():
    # A 2 m x 2 m quad 3 m ahead, normal towards the camera (u x v = -z): every ray through it
    # has optical-axis depth 3; rays outside its 1 m half-size miss (-1, inf).
    quad = Quad((0.0, 0.0, 3.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, 1.0)
    camera = PinholeCamera(9, 9, 2.0, 2.0, 4.0, 4.0)  # pixel x at (x - 4) / 2 * 3 m
    index, depth, _ = nearest_hits([quad], camera, np.eye(4))
    assert depth[4, 4] == pytest.approx(3.0)
    # Column 5: x = 0.5 * 3 = 1.5 m > 1 m -> missed; column 4 +- 0 hits.
    assert np.isinf(depth[4, 7]) and index[4, 7] == -1
    assert index[4, 4] == 0
    # Seen from behind (camera looking back at it from z = 6) the one-sided quad is culled.
    behind = look_at(np.array([[0.0, 0.0, 6.0]]), np.zeros(3))[0]
    assert nearest_hits([quad], camera, behind)[1][4, 4] == np.inf


def test_sphere_depth_at_the_centre_pixel():
    # Sphere of radius 0.5 centred 4 m ahead: the central ray hits at depth 3.5.
    camera = PinholeCamera(5, 5, 10.0, 10.0, 2.0, 2.0)
    _, depth, _ = nearest_hits([Sphere((0.0, 0.0, 4.0), 0.5)], camera, np.eye(4))
    assert depth[2, 2] == pytest.approx(3.5, abs=1e-5)


def test_room_faces_point_inwards_and_box_faces_outwards():
    room = box_faces((-1, -1, -1), (1, 1, 1), inward=True)
    box = box_faces((-1, -1, -1), (1, 1, 1))
    for face_in, face_out in zip(room, box, strict=True):
        center = np.asarray(face_in.center)
        assert face_in.normal @ center < 0 < face_out.normal @ center
    with pytest.raises(UsageError):
        box_faces((0, 0, 0), (1, 0, 1))


@pytest.mark.parametrize("name", sorted(SCENES))
def test_scene_dynamic_range_texture_and_depth(name):
    scene = get_scene(name)
    radiance, depth = scene.render(DAVIS, front_view(scene))
    assert radiance.shape == (260, 346, 3) and radiance.dtype == np.float32
    luminance = radiance @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    darkest, brightest = np.percentile(luminance, [0.1, 99.9])
    assert brightest / darkest >= 1e4
    # The brightest surface (the emitter: pixels above a tenth of the peak) is textured.
    emitter = luminance[luminance > luminance.max() / 10]
    assert emitter.std() / emitter.mean() > 0.08
    # ... and so is the darkest part of the view (its darkest 2 % of pixels).
    shadow = luminance[luminance <= np.percentile(luminance, 2)]
    assert shadow.std() / shadow.mean() > 0.05
    # Real depth for parallax: the far part of the view is at least twice as deep as the near.
    near, far = np.percentile(depth[np.isfinite(depth)], [2, 98])
    assert far / near > 2
    # Enough texture for SIFT on the training-exposure LDR image.
    assert len(cv2.SIFT_create().detect(ldr_luminance(radiance), None)) > 150


def test_render_is_deterministic_and_other_poses_differ():
    scene = get_scene("room")
    c2w = front_view(scene)
    first, _ = scene.render(DAVIS, c2w)
    second, _ = scene.render(DAVIS, c2w.copy())
    assert first.tobytes() == second.tobytes()
    moved = c2w.copy()
    moved[0, 3] += 0.05
    assert not np.array_equal(scene.render(DAVIS, moved)[0], first)


def test_unknown_scene_and_bad_pose():
    with pytest.raises(UsageError, match="unknown emulator scene"):
        get_scene("garden")
    with pytest.raises(UsageError, match="4x4"):
        get_scene("room").render(DAVIS, np.eye(3))


def ldr_luminance(radiance):
    luminance = radiance @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    return ((luminance / (luminance + 1)) ** (1 / 2.2) * 255).astype(np.uint8)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_sift_matches_between_distant_training_views(name):
    # Views 0 and 5 of the 16-view grid (one row and a column apart) share many SIFT matches that
    # satisfy one epipolar geometry: what COLMAP needs to register them.
    from davis_io.emulator import EmulatedCamera

    camera = EmulatedCamera(name)
    poses = camera.trajectory.c2w(camera.config.frame_windows()[[0, 5], 1])
    images = [ldr_luminance(camera.scene.render(DAVIS, pose)[0]) for pose in poses]
    sift = cv2.SIFT_create()
    (points_a, features_a), (points_b, features_b) = [
        sift.detectAndCompute(i, None) for i in images
    ]
    pairs = cv2.BFMatcher().knnMatch(features_a, features_b, k=2)
    good = [first for first, second in pairs if first.distance < 0.8 * second.distance]
    a = np.float32([points_a[m.queryIdx].pt for m in good])
    b = np.float32([points_b[m.trainIdx].pt for m in good])
    _, inliers = cv2.findFundamentalMat(a, b, cv2.FM_RANSAC, 1.0, 0.999)
    assert inliers.sum() >= 40


@pytest.mark.parametrize("color_filter", [ColorFilter.RGGB, ColorFilter.GBRG, ColorFilter.MONO])
def test_channel_render_equals_the_filtered_rgb_render(color_filter):
    scene = get_scene("lamp")
    pose = front_view(scene)
    radiance, _ = scene.render(DAVIS, pose)
    expected = through_filter(radiance, filter_weights(color_filter, 260, 346))
    channels = filter_channels(color_filter, 260, 346)
    np.testing.assert_allclose(scene.render_channel(DAVIS, pose, channels), expected, rtol=1e-5)
    assert filter_channels(ColorFilter.RGWB, 4, 4) is None
