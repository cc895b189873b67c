"""Ground truth of an emulated recording: building it, and the session's ``truth/`` folder.

Layout written by :func:`save_truth` (the contract with the pose estimator and the trainer)::

    truth/truth.h5
        attrs: scene, seed, crf (curve name), exposure_us (training exposure),
               test_exposures_s (5: x1/16, x1/4, x1, x4, x16 of it), color_filter,
               extent (largest distance between two training camera rest positions, metres;
               the view spacing when there is one view),
               gain_per_s (response input = gain * radiance * exposure_s),
               depth_range_m (nearest and farthest depth in the mid-exposure training views)
        /intrinsics          float64 (4,)            fx, fy, cx, cy (pixel centres at integers)
        /train/time_us       int64   (F, S)          sub-frame times of each training exposure
        /train/c2w           float64 (F, S, 4, 4)    true poses at those times (OpenCV axes)
        /train/sharp_hdr     float32 (F, H, W, C)    linear radiance at mid-exposure
        /test/c2w            float64 (T, 4, 4)       held-out views
        /test/hdr            float32 (T, H, W, C)    sharp linear radiance
        /test/ldr            uint8   (T, 5, H, W, C) through the true response, full channels
        /crf/log_exposure    float64 (K,)            ln(radiance * exposure_s)
        /crf/value           float64 (K,)            LDR value in [0, 1]
        /path/time_us        int64   (N,)            every millisecond of the recording
        /path/c2w            float64 (N, 4, 4)       true poses then (see Truth.c2w_at)
    truth/test/hdr/{i:03d}.exr       float32 OpenEXR (RGB, or Y for monochrome)
    truth/test/ldr/x{factor}/{i:03d}.png   8-bit, factor in 1_16, 1_4, 1, 4, 16

C is 3 (RGB) for colour sensors and 1 (luminance) for monochrome ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import h5py
import numpy as np
import OpenEXR

from davis_io.emulator.aps import subframe_times
from davis_io.emulator.colorfilter import sensor_channels
from davis_io.emulator.response import apply_response, response_table
from davis_io.emulator.scene import Scene
from davis_io.emulator.trajectory import Trajectory, grid_positions, look_at
from davis_io.errors import SessionError
from davis_io.poses.align import interpolate_poses
from davis_io.types import ColorFilter

if TYPE_CHECKING:
    from davis_io.emulator.source import EmulatorConfig

__all__ = ["TEST_EXPOSURE_FACTORS", "Truth", "build_truth", "load_truth", "save_truth"]

TEST_EXPOSURE_FACTORS = (1 / 16, 1 / 4, 1.0, 4.0, 16.0)
"""The paper's exposure bracket, as multiples of the training exposure."""

_FACTOR_NAMES = ("1_16", "1_4", "1", "4", "16")
_ARRAYS = {
    "intrinsics": "intrinsics",
    "train_time_us": "train/time_us",
    "train_c2w": "train/c2w",
    "train_sharp_hdr": "train/sharp_hdr",
    "test_c2w": "test/c2w",
    "test_hdr": "test/hdr",
    "test_ldr": "test/ldr",
    "crf_log_exposure": "crf/log_exposure",
    "crf_value": "crf/value",
    "path_time_us": "path/time_us",
    "path_c2w": "path/c2w",
}
_PATH_STEP_US = 1000


@dataclass
class Truth:
    """What really happened in an emulated recording (shapes in the module docstring)."""

    scene: str
    seed: int
    crf: str
    exposure_us: int
    test_exposures_s: np.ndarray
    color_filter: ColorFilter
    extent: float
    gain_per_s: float
    depth_range_m: np.ndarray
    intrinsics: np.ndarray
    train_time_us: np.ndarray
    train_c2w: np.ndarray
    train_sharp_hdr: np.ndarray
    test_c2w: np.ndarray
    test_hdr: np.ndarray
    test_ldr: np.ndarray
    crf_log_exposure: np.ndarray
    crf_value: np.ndarray
    path_time_us: np.ndarray
    path_c2w: np.ndarray

    def c2w_at(self, times_us: np.ndarray) -> np.ndarray:
        """True camera-to-world ``(Q, 4, 4)`` at any times ``(Q,)`` µs of the recording.

        Interpolated (slerp and linear) from the path sampled every millisecond; with the
        shake's frequencies (below 6 Hz) the error stays under 1e-5 rad (0.003 px at 280 px focal).
        """
        return interpolate_poses(self.path_time_us, self.path_c2w, np.asarray(times_us))


def _render_views(
    scene: Scene, config: EmulatorConfig, poses: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    camera = config.camera
    shape = (len(poses), camera.height, camera.width)
    hdr = np.empty((*shape, 3 if config.color_filter.is_color else 1), np.float32)
    depth = np.empty(shape, np.float32)
    for index, c2w in enumerate(poses):
        radiance, depth[index] = scene.render(camera, c2w)
        hdr[index] = sensor_channels(radiance, config.color_filter)
    return hdr, depth


def _ldr_bracket(hdr: np.ndarray, config: EmulatorConfig) -> np.ndarray:
    exposures_s = config.exposure_us * 1e-6 * np.asarray(TEST_EXPOSURE_FACTORS)
    x = config.gain_per_s * exposures_s[None, :, None, None, None] * hdr[:, None]
    return np.round(apply_response(config.response, x) * 255).astype(np.uint8)


def build_truth(config: EmulatorConfig, scene: Scene, trajectory: Trajectory) -> Truth:
    """Render the ground truth of a recording.

    Args:
        config: the recording's :class:`~davis_io.emulator.source.EmulatorConfig`.
        scene: its scene.
        trajectory: its true camera path.
    """
    windows = config.frame_windows()
    times = np.stack([subframe_times(int(w[1]), int(w[2]), config.subframes) for w in windows])
    train_c2w = trajectory.c2w(times.ravel()).reshape(*times.shape, 4, 4)
    sharp_hdr, train_depth = _render_views(scene, config, train_c2w[:, config.subframes // 2])
    baseline = config.baseline_m or scene.baseline
    test_positions = grid_positions(
        config.test_views, np.asarray(scene.camera_center), baseline, offset=True
    )
    test_c2w = look_at(test_positions, scene.target) if config.test_views else np.empty((0, 4, 4))
    test_hdr, _ = _render_views(scene, config, test_c2w)
    log_exposure, value = response_table(config.response, config.gain_per_s)
    rest = trajectory.positions
    extent = max(float(np.max(np.linalg.norm(rest[:, None] - rest[None], axis=2))), baseline)
    finite = train_depth[np.isfinite(train_depth)]
    path_time_us = np.arange(0, config.end_us + 1, _PATH_STEP_US, dtype=np.int64)
    return Truth(
        scene=config.scene,
        seed=config.seed,
        crf=config.response,
        exposure_us=config.exposure_us,
        test_exposures_s=config.exposure_us * 1e-6 * np.asarray(TEST_EXPOSURE_FACTORS),
        color_filter=config.color_filter,
        extent=extent,
        gain_per_s=config.gain_per_s,
        depth_range_m=np.array([finite.min(), finite.max()], np.float64),
        intrinsics=config.camera.intrinsics,
        train_time_us=times,
        train_c2w=train_c2w,
        train_sharp_hdr=sharp_hdr,
        test_c2w=test_c2w,
        test_hdr=test_hdr,
        test_ldr=_ldr_bracket(test_hdr, config),
        crf_log_exposure=log_exposure,
        crf_value=value,
        path_time_us=path_time_us,
        path_c2w=trajectory.c2w(path_time_us),
    )


def _write_exr(path: Path, image: np.ndarray) -> None:
    name = "RGB" if image.shape[-1] == 3 else "Y"
    pixels = np.ascontiguousarray(image if name == "RGB" else image[..., 0], np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {name: pixels}).write(str(path))


def save_truth(truth: Truth, folder: str | Path) -> Path:
    """Write ``truth.h5`` and the viewable EXR and PNG files into ``folder`` (the ``truth/`` dir).

    Returns:
        The folder.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with h5py.File(folder / "truth.h5", "w") as h5:
        h5.attrs.update(
            {
                "scene": truth.scene,
                "seed": truth.seed,
                "crf": truth.crf,
                "exposure_us": truth.exposure_us,
                "test_exposures_s": truth.test_exposures_s,
                "color_filter": truth.color_filter.value,
                "extent": truth.extent,
                "gain_per_s": truth.gain_per_s,
                "depth_range_m": truth.depth_range_m,
            }
        )
        for attribute, path in _ARRAYS.items():
            h5.create_dataset(
                path, data=getattr(truth, attribute), compression="gzip", compression_opts=1
            )
    for index, hdr in enumerate(truth.test_hdr):
        (folder / "test" / "hdr").mkdir(parents=True, exist_ok=True)
        _write_exr(folder / "test" / "hdr" / f"{index:03d}.exr", hdr)
        for factor, ldr in zip(_FACTOR_NAMES, truth.test_ldr[index], strict=True):
            ldr_dir = folder / "test" / "ldr" / f"x{factor}"
            ldr_dir.mkdir(parents=True, exist_ok=True)
            cv2.imwrite(
                str(ldr_dir / f"{index:03d}.png"), ldr[..., ::-1] if ldr.shape[-1] == 3 else ldr
            )
    return folder


def load_truth(folder: str | Path) -> Truth:
    """Read a ``truth/`` folder (or a session folder that contains one).

    Raises:
        SessionError: no ``truth.h5`` there, or it lacks a field.
    """
    folder = Path(folder)
    if not (folder / "truth.h5").exists() and (folder / "truth" / "truth.h5").exists():
        folder = folder / "truth"
    path = folder / "truth.h5"
    if not path.exists():
        raise SessionError(f"{path}: no ground truth here; only emulated sessions have truth/")
    try:
        with h5py.File(path, "r") as h5:
            attrs = dict(h5.attrs)
            arrays = {attribute: h5[name][()] for attribute, name in _ARRAYS.items()}
        return Truth(
            scene=str(attrs["scene"]),
            seed=int(attrs["seed"]),
            crf=str(attrs["crf"]),
            exposure_us=int(attrs["exposure_us"]),
            test_exposures_s=np.asarray(attrs["test_exposures_s"], np.float64),
            color_filter=ColorFilter(str(attrs["color_filter"])),
            extent=float(attrs["extent"]),
            gain_per_s=float(attrs["gain_per_s"]),
            depth_range_m=np.asarray(attrs["depth_range_m"], np.float64),
            **arrays,
        )
    except KeyError as missing:
        raise SessionError(f"{path}: missing {missing}; rewrite it with save_truth") from None
    except OSError as error:
        raise SessionError(f"{path}: cannot be read as HDF5 ({error})") from None
