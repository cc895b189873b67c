"""Rendering the ground truth of an emulated recording (its format: ``davis_io.session.truth``)."""

from __future__ import annotations

import numpy as np

from davis_io.emulator.aps import ApsSettings, linear_noise, subframe_times
from davis_io.emulator.colorfilter import sensor_channels
from davis_io.emulator.config import EmulatorConfig
from davis_io.emulator.dvs import DvsPixels
from davis_io.emulator.lens_view import LensView
from davis_io.emulator.response import response_table
from davis_io.emulator.scene import Scene
from davis_io.emulator.sensor import Sensor
from davis_io.emulator.trajectory import Trajectory, grid_positions, look_at
from davis_io.session.truth import TEST_EXPOSURE_FACTORS, Truth

__all__ = ["build_truth"]

_PATH_STEP_US = 1000


def _render_views(
    scene: Scene, config: EmulatorConfig, sensor: Sensor, poses: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    view = LensView(config.optics)
    shape = (len(poses), config.height, config.width)
    hdr = np.empty((*shape, 3 if sensor.color_filter.is_color else 1), np.float32)
    depth = np.empty(shape, np.float32)
    for index, c2w in enumerate(poses):
        radiance, depth[index] = view.render(scene, c2w)
        hdr[index] = sensor_channels(radiance, sensor.color_filter)
    return hdr, depth


def _ldr_bracket(hdr: np.ndarray, config: EmulatorConfig, sensor: Sensor) -> np.ndarray:
    exposures_s = config.exposure_us * 1e-6 * np.asarray(TEST_EXPOSURE_FACTORS)
    x = config.gain_per_s * exposures_s[None, :, None, None, None] * hdr[:, None]
    return np.round(sensor.response(x) * 255).astype(np.uint8)


def build_truth(
    config: EmulatorConfig,
    sensor: Sensor,
    scene: Scene,
    trajectory: Trajectory,
    pixels: DvsPixels,
) -> Truth:
    """Render the ground truth of a recording.

    Args:
        config: the recording's settings.
        sensor: its sensor.
        scene: its scene.
        trajectory: its true camera path.
        pixels: its DVS pixel array as drawn (the per-pixel thresholds).
    """
    windows = config.frame_windows()
    times = np.stack([subframe_times(int(w[1]), int(w[2]), config.subframes) for w in windows])
    train_c2w = trajectory.c2w(times.ravel()).reshape(*times.shape, 4, 4)
    sharp_hdr, train_depth = _render_views(
        scene, config, sensor, train_c2w[:, config.subframes // 2]
    )
    baseline = config.baseline_m or scene.baseline
    test_positions = grid_positions(
        config.test_views, np.asarray(scene.camera_center), baseline, offset=True
    )
    test_c2w = look_at(test_positions, scene.target) if config.test_views else np.empty((0, 4, 4))
    test_hdr, _ = _render_views(scene, config, sensor, test_c2w)
    log_exposure, value = response_table(sensor.response, config.gain_per_s)
    rest = trajectory.positions
    extent = max(float(np.max(np.linalg.norm(rest[:, None] - rest[None], axis=2))), baseline)
    finite = train_depth[np.isfinite(train_depth)]
    path_time_us = np.arange(0, config.end_us + 1, _PATH_STEP_US, dtype=np.int64)
    return Truth(
        scene=config.scene,
        seed=config.seed,
        crf=sensor.response.family,
        exposure_us=config.exposure_us,
        test_exposures_s=config.exposure_us * 1e-6 * np.asarray(TEST_EXPOSURE_FACTORS),
        color_filter=sensor.color_filter,
        extent=extent,
        gain_per_s=config.gain_per_s,
        depth_range_m=np.array([finite.min(), finite.max()], np.float64),
        intrinsics=config.camera.intrinsics,
        train_time_us=times,
        train_c2w=train_c2w,
        train_sharp_hdr=sharp_hdr,
        test_c2w=test_c2w,
        test_hdr=test_hdr,
        test_ldr=_ldr_bracket(test_hdr, config, sensor),
        crf_log_exposure=log_exposure,
        crf_value=value,
        path_time_us=path_time_us,
        path_c2w=trajectory.c2w(path_time_us),
        camera=config.to_json(),
        sensor={
            **sensor.to_json(pixels, config.dvs_step_us),
            "frame_noise": linear_noise(
                sensor.response,
                ApsSettings(
                    sensor.response,
                    config.gain_per_s,
                    electrons_per_unit=ApsSettings.electrons_per_unit if config.aps_noise else 0,
                ),
            ),
        },
        pixel_threshold_on=pixels.threshold_on.reshape(config.height, config.width),
        pixel_threshold_off=pixels.threshold_off.reshape(config.height, config.width),
    )
