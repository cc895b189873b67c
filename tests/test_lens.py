"""Lenses: calibration files read, the distortion model, rays and the emulator's distorted views."""

import json

import numpy as np
import pytest
import torch

from davis_io.emulator.lens_view import LensView, lens_distortion
from davis_io.emulator.raytrace import Quad, nearest_hits
from davis_io.errors import UsageError
from davis_io.geometry import nerfstudio_transforms
from davis_io.lens import Lens, read_camera_calibration, write_camera_calibration
from seenerf.render.rays import camera_rays

# A DAVIS346 behind its usual small lens, as DV's calibration reports such a camera.
DAVIS_LENS = Lens(346, 260, 248.16, 247.77, 180.66, 128.10, (-0.358, 0.115, -0.0004, -0.0002))

DV_XML = """<?xml version="1.0"?>
<opencv_storage>
<DAVIS346_00000499>
  <camera_matrix type_id="opencv-matrix">
    <rows>3</rows>
    <cols>3</cols>
    <dt>d</dt>
    <data>
      248.16 0. 180.66 0. 247.77 128.10 0. 0. 1.</data></camera_matrix>
  <distortion_coefficients type_id="opencv-matrix">
    <rows>1</rows>
    <cols>5</cols>
    <dt>d</dt>
    <data>
      -0.358 0.115 -0.0004 -0.0002 0.</data></distortion_coefficients>
  <image_width>346</image_width>
  <image_height>260</image_height>
  <type>camera</type>
  <use_fisheye_model>0</use_fisheye_model>
</DAVIS346_00000499>
</opencv_storage>
"""

OPENCV_YAML = """%YAML:1.0
---
image_width: 346
image_height: 260
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 250., 0., 172., 0., 251., 130., 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -0.2, 0.05, 0.001, 0.002, 0.01 ]
"""


def test_a_dv_calibration_file_gives_the_lens_it_states(tmp_path):
    (tmp_path / "calibration_camera_DAVIS346.xml").write_text(DV_XML)
    lens = read_camera_calibration(tmp_path / "calibration_camera_DAVIS346.xml", 346, 260)
    assert lens == DAVIS_LENS  # the trailing k3 = 0 dropped


def test_opencv_yaml_colmap_and_json_files_give_their_lens(tmp_path):
    (tmp_path / "camera.yaml").write_text(OPENCV_YAML)
    lens = read_camera_calibration(tmp_path / "camera.yaml", 346, 260)
    assert (lens.fx, lens.fy, lens.cx, lens.cy) == (250.0, 251.0, 172.0, 130.0)
    assert lens.distortion == (-0.2, 0.05, 0.001, 0.002, 0.01)
    # COLMAP puts pixel centres at +0.5: its principal point 173.0 is the session's 172.5.
    (tmp_path / "cameras.txt").write_text(
        "# Camera list with one line of data per camera:\n"
        "1 OPENCV 346 260 280 281 173.0 130.0 -0.1 0.02 0.001 -0.001\n"
    )
    lens = read_camera_calibration(tmp_path / "cameras.txt", 346, 260)
    assert (lens.fx, lens.fy, lens.cx, lens.cy) == (280.0, 281.0, 172.5, 129.5)
    assert lens.distortion == (-0.1, 0.02, 0.001, -0.001)
    (tmp_path / "k.json").write_text('{"fx": 280, "fy": 281, "cx": 172.5, "cy": 129.5}')
    assert read_camera_calibration(tmp_path / "k.json", 346, 260) == Lens(
        346, 260, 280, 281, 172.5, 129.5
    )


def test_what_the_writer_writes_the_reader_reads(tmp_path):
    path = write_camera_calibration(DAVIS_LENS, tmp_path / "camera.xml", "DAVIS346_00000001")
    assert read_camera_calibration(path, 346, 260) == DAVIS_LENS


@pytest.mark.parametrize(
    ("name", "text", "says"),
    [
        ("other.xml", DV_XML, "for 346x260 images, the camera's are 240x180"),
        ("fisheye.xml", DV_XML.replace("<use_fisheye_model>0", "<use_fisheye_model>1"), "fisheye"),
        ("empty.yaml", "%YAML:1.0\n---\nimage_width: 346\n", "no camera_matrix"),
        ("cameras.txt", "1 THIN_PRISM_FISHEYE 346 260 1 2 3\n", "not one of COLMAP's"),
        ("camera.ini", "fx=1", "not a calibration file seecap reads"),
        ("missing.xml", None, "no such calibration file"),
    ],
)
def test_a_calibration_file_that_cannot_serve_says_why(tmp_path, name, text, says):
    if text is not None:
        (tmp_path / name).write_text(text)
    width, height = (240, 180) if name == "other.xml" else (346, 260)
    with pytest.raises(UsageError, match=says) as error:
        read_camera_calibration(tmp_path / name, width, height)
    assert name in str(error.value)


def test_the_distortion_model_matches_a_hand_computed_point():
    lens = Lens(346, 260, 200.0, 200.0, 170.0, 130.0, (-0.2, 0.0, 0.01, 0.0))
    # (x, y) = (0.5, 0.25): s = 0.3125, radial 1 - 0.0625 = 0.9375;
    # dx = 2 p1 x y = 0.0025, dy = p1 (s + 2 y^2) = 0.004375.
    expected = np.array(
        [[170 + 200 * (0.5 * 0.9375 + 0.0025), 130 + 200 * (0.25 * 0.9375 + 0.004375)]]
    )
    assert np.allclose(lens.project([[0.5, 0.25]]), expected, atol=1e-9)
    assert np.allclose(lens.normalised(expected), [[0.5, 0.25]], atol=1e-9)


def test_the_fits_rays_follow_the_lens_as_opencv_undistorts():
    rows, columns = np.mgrid[0:260:7, 0:346:7]
    pixels = np.stack([columns.ravel(), rows.ravel()], axis=1).astype(np.float64)
    _, directions = camera_rays(
        torch.eye(4, dtype=torch.float64),
        torch.tensor(DAVIS_LENS.intrinsics),
        torch.tensor(pixels[:, 0]),
        torch.tensor(pixels[:, 1]),
        torch.tensor(DAVIS_LENS.coefficients),
    )
    expected = DAVIS_LENS.normalised(pixels)
    # Within a thousandth of a pixel everywhere, the corners included (0.19 rad off a pinhole).
    assert np.abs(directions[:, :2].numpy() - expected).max() * DAVIS_LENS.fx < 1e-3
    assert np.abs(expected[0] - (pixels[0] - DAVIS_LENS.intrinsics[2:]) / 248.0).max() > 0.1


def test_a_pinhole_lens_gives_the_plain_rays():
    intrinsics = torch.tensor([280.0, 281.0, 172.5, 129.5])
    u, v = torch.tensor([0.0, 345.0]), torch.tensor([0.0, 259.0])
    _, plain = camera_rays(torch.eye(4), intrinsics, u, v)
    _, empty = camera_rays(torch.eye(4), intrinsics, u, v, torch.zeros(0))
    assert torch.equal(plain, empty)
    assert torch.allclose(plain[1], torch.tensor([172.5 / 280, 129.5 / 281, 1.0]))


class _QuadScene:
    """A scene of quads whose radiance is 1 on a surface and 0 elsewhere."""

    def __init__(self, quads):
        self.quads = quads

    def render(self, camera, c2w):
        index, depth, _ = nearest_hits(self.quads, camera, c2w)
        radiance = np.repeat((index >= 0)[..., None], 3, axis=2).astype(np.float32)
        return radiance, depth


def test_an_emulated_lens_shows_an_edge_where_the_lens_puts_it():
    lens = Lens(346, 260, 280.0, 280.0, 172.5, 129.5, lens_distortion("random", 5))
    # A wall's edge at x / z = 0.45 (3 m away): the pinhole puts it at column 298.5.
    wall = Quad((1.35 + 2.0, 0.0, 3.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 2.0, 3.0)
    radiance, depth = LensView(lens).render(_QuadScene([wall]), np.eye(4))
    assert radiance.shape == (260, 346, 3) and depth.shape == (260, 346)
    for y in (-0.35, 0.0, 0.3):
        column, row = lens.project([[0.45, y]])[0]
        seen = radiance[int(round(row)), :, 0]
        edge = np.flatnonzero(seen > 0.5)[0] - 0.5  # halfway between the last 0 and first 1
        assert abs(edge - column) < 1.0, (y, edge, column)
    pinhole_column = 172.5 + 0.45 * 280.0
    assert lens.project([[0.45, 0.3]])[0, 0] < pinhole_column - 5  # barrel: pulled inwards


def test_random_lenses_never_fold_the_image_and_bad_ones_are_refused():
    for seed in range(20):
        k1, k2, p1, p2 = lens_distortion("random", seed)
        assert -0.35 <= k1 <= -0.08 and k2 > 0.45 * k1 * k1 and max(abs(p1), abs(p2)) <= 0.002
    assert lens_distortion("random", 3) == lens_distortion("random", 3)
    assert lens_distortion("pinhole", 3) == ()
    assert lens_distortion("-0.1,0.01,0,0", 0) == (-0.1, 0.01, 0.0, 0.0)
    for bad in ("fisheye", "-0.1,0.01", "2,0,0,0"):
        with pytest.raises(UsageError, match="pinhole, random"):
            lens_distortion(bad, 0)
    folding = Lens(346, 260, 280.0, 280.0, 172.5, 129.5, (-0.45, 0.0, 0.0, 0.0))
    with pytest.raises(UsageError, match="folds the image over"):
        LensView(folding).render(_QuadScene([]), np.eye(4))


def test_nerfstudio_transforms_carry_the_lens():
    payload = nerfstudio_transforms(
        np.eye(4)[None], DAVIS_LENS.intrinsics, DAVIS_LENS.coefficients, (260, 346), ["a.png"]
    )
    assert (payload["k1"], payload["k2"], payload["p1"], payload["p2"]) == DAVIS_LENS.distortion
    assert "k3" not in payload
    with_k3 = nerfstudio_transforms(
        np.eye(4)[None], DAVIS_LENS.intrinsics, [-0.2, 0.05, 0, 0, 0.01], (260, 346), ["a.png"]
    )
    assert with_k3["k3"] == 0.01
    json.dumps(with_k3)


def test_a_recording_keeps_the_lens_it_was_given_and_refuses_one_for_another_camera(tmp_path):
    from davis_io.emulator import EmulatedCamera
    from davis_io.session import Session
    from davis_io.session.recorder import record

    small = {"frames": 2, "test_views": 0, "width": 64, "height": 48, "focal_px": 50.0}
    (tmp_path / "lens.json").write_text('{"fx": 50, "fy": 51, "cx": 31.5, "cy": 23.5, "k1": -0.1}')
    record(EmulatedCamera(**small), tmp_path / "s", camera_calibration=tmp_path / "lens.json")
    with Session.open(tmp_path / "s") as session:
        stated = Lens.from_json(session.manifest.lens)
    assert stated == Lens(64, 48, 50.0, 51.0, 31.5, 23.5, (-0.1,))
    write_camera_calibration(DAVIS_LENS, tmp_path / "davis.xml", "DAVIS346_00000499")
    with pytest.raises(UsageError, match="for 346x260 images, the camera's are 64x48"):
        record(EmulatedCamera(**small), tmp_path / "t", camera_calibration=tmp_path / "davis.xml")
    assert not (tmp_path / "t").exists()  # refused before anything was recorded


class _RayEcho(torch.nn.Module):
    """A stand-in field whose log radiance is the ray's direction: renders show each ray."""

    def __init__(self):
        super().__init__()
        self.unused = torch.nn.Parameter(torch.zeros(1))

    def render_log_radiance(self, origins, directions):
        return directions


def test_renders_follow_the_lens_or_a_pinhole_on_request():
    from seenerf.eval.views import render_log_image

    lens = Lens(40, 30, 30.0, 30.0, 19.5, 14.5, (-0.2, 0.03, 0.001, 0.0))
    size = (lens.height, lens.width)
    seen = render_log_image(
        _RayEcho(), np.eye(4), lens.intrinsics, size, distortion=lens.coefficients
    )
    assert np.abs(seen[..., :2] - lens.pixel_rays()).max() < 1e-5
    straight = render_log_image(_RayEcho(), np.eye(4), lens.intrinsics, size)
    columns = (np.arange(40) - 19.5) / 30.0
    assert np.allclose(straight[0, :, 0], columns, atol=1e-6)
    assert np.abs(seen[0, :, 0] - columns).max() > 0.05  # the corners differ by the lens
