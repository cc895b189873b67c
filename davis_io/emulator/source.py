"""``EmulatedCamera``: a DAVIS346 packet source rendering a built-in scene along a shaky path.

Timeline (integer µs from 0): the DVS runs from 0 to the end in steps of ``dvs_step_us``; frame
``k`` starts its readout (SOF, reset read) at ``lead_us + k * frame_interval_us``, exposes from
``readout_us`` later for ``exposure_us`` (both ends included), and ends its readout (EOF) another
``readout_us`` after the exposure. Packets cover ``packet_us`` of device time each and carry the
events of that time, the frames whose readout ended in it, the IMU samples and the four APS
triggers of each frame (readout start, exposure start, exposure end, readout end).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict, dataclass
from functools import cached_property

import numpy as np

from davis_io.colorfilter import filter_channels, filter_weights
from davis_io.emulator.aps import ApsSettings, expose, subframe_times
from davis_io.emulator.colorfilter import through_filter
from davis_io.emulator.dvs import DVS_PRESETS, DvsPixels
from davis_io.emulator.raytrace import PinholeCamera
from davis_io.emulator.response import RESPONSE_CURVES
from davis_io.emulator.scene import Scene
from davis_io.emulator.scenes import get_scene
from davis_io.emulator.trajectory import Shake, Trajectory, grid_positions, imu_readings
from davis_io.emulator.truth import Truth, build_truth
from davis_io.errors import UsageError
from davis_io.types import (
    TRIGGER_DTYPE,
    Closing,
    ColorFilter,
    Frame,
    Packet,
    SourceInfo,
    TriggerKind,
    empty_events,
    empty_imu,
)

__all__ = ["EmulatedCamera", "EmulatorConfig"]


@dataclass(frozen=True)
class EmulatorConfig:
    """Everything that defines an emulated recording; the same config gives the same bytes.

    Attributes:
        scene: built-in scene name (``room``, ``lamp``, ``corridor``).
        frames: number of training frames (views).
        test_views: number of held-out views in the truth.
        exposure_us: APS exposure of every frame, µs.
        frame_interval_us: SOF to SOF, µs; 0 means ``exposure_us + 50 ms``.
        readout_us: reset read before and signal read after each exposure, µs.
        lead_us: device time before the first frame's readout, µs.
        subframes: renders per exposure for the APS integral (trapezoid weights).
        dvs_step_us: time between DVS samples, µs.
        dvs_preset: DVS pixel preset (``clean``, ``noisy``, ``v2e-clean``, ``v2e-noisy``).
        response: APS response curve (``reinhard_gamma``, ``film``).
        aps_noise: add shot and read noise to frames.
        color_filter: colour filter of APS and DVS pixels.
        width: sensor columns.
        height: sensor rows.
        focal_px: focal length in pixels (principal point at the image centre).
        shake: RMS hand-shake rotation, degrees.
        shake_translation_m: RMS hand-shake translation, metres.
        baseline_m: spacing of capture positions, metres; 0 takes the scene's own.
        seed: seeds the shake, the pixel mismatch and all noise.
        packet_us: device time per packet, µs.
        imu_rate_hz: IMU samples per second (ideal gyro and accelerometer, camera axes); 0 for
            none.
    """

    scene: str = "room"
    frames: int = 16
    test_views: int = 8
    exposure_us: int = 150_000
    frame_interval_us: int = 0
    readout_us: int = 8_000
    lead_us: int = 20_000
    subframes: int = 17
    dvs_step_us: int = 2_000
    dvs_preset: str = "noisy"
    response: str = "reinhard_gamma"
    aps_noise: bool = True
    color_filter: ColorFilter = ColorFilter.RGGB
    width: int = 346
    height: int = 260
    focal_px: float = 280.0
    shake: float = 0.8
    shake_translation_m: float = 0.002
    baseline_m: float = 0.0
    seed: int = 0
    packet_us: int = 10_000
    imu_rate_hz: int = 1000

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "color_filter", ColorFilter(self.color_filter))
        except ValueError:
            names = ", ".join(f.value for f in ColorFilter)
            raise UsageError(f"colour filter {self.color_filter!r} is not one of {names}") from None
        if self.frame_interval_us == 0:
            object.__setattr__(self, "frame_interval_us", self.exposure_us + 50_000)
        problems = []
        if self.width < 2 or self.height < 2 or self.focal_px <= 0:
            problems.append("width and height of at least 2 pixels and a positive focal length")
        if self.shake < 0 or self.shake_translation_m < 0 or self.baseline_m < 0:
            problems.append("shake, shake translation and baseline must not be negative")
        if self.frames < 1 or self.test_views < 0 or self.subframes < 2:
            problems.append("frames >= 1, test_views >= 0 and subframes >= 2 are needed")
        if min(self.exposure_us, self.readout_us, self.dvs_step_us, self.packet_us) <= 0:
            problems.append("exposure, readout, DVS step and packet durations must be positive")
        if not 0 <= self.imu_rate_hz <= 1_000_000:
            problems.append(f"IMU rate {self.imu_rate_hz} Hz must be within 0..1000000")
        shortest_us = self.exposure_us + 2 * self.readout_us + self.dvs_step_us
        if self.frame_interval_us < shortest_us:
            problems.append(
                f"frame interval {self.frame_interval_us} µs is shorter than exposure + two "
                f"readouts + one DVS step ({shortest_us} µs)"
            )
        if self.dvs_preset not in DVS_PRESETS:
            problems.append(
                f"DVS preset {self.dvs_preset!r} is not one of {', '.join(DVS_PRESETS)}"
            )
        if self.response not in RESPONSE_CURVES:
            problems.append(
                f"response {self.response!r} is not one of {', '.join(RESPONSE_CURVES)}"
            )
        if problems:
            raise UsageError("emulator settings: " + "; ".join(problems))

    @property
    def camera(self) -> PinholeCamera:
        """The sensor's pinhole intrinsics."""
        return PinholeCamera(
            self.width,
            self.height,
            self.focal_px,
            self.focal_px,
            (self.width - 1) / 2,
            (self.height - 1) / 2,
        )

    @property
    def gain_per_s(self) -> float:
        """Sensor gain: 1 / training exposure in seconds (radiance 1 maps to response input 1)."""
        return 1e6 / self.exposure_us

    def frame_windows(self) -> np.ndarray:
        """``(F, 4)`` int64 readout start, exposure start, exposure end, readout end, µs."""
        start = self.lead_us + np.arange(self.frames, dtype=np.int64) * self.frame_interval_us
        exposure_start = start + self.readout_us
        exposure_end = exposure_start + self.exposure_us
        return np.stack([start, exposure_start, exposure_end, exposure_end + self.readout_us], 1)

    @property
    def end_us(self) -> int:
        """Device time of the last DVS sample, µs."""
        return int(self.frame_windows()[-1, 3]) + self.lead_us


def _build_trajectory(config: EmulatorConfig, scene: Scene) -> Trajectory:
    """The true camera path of a recording with these settings."""
    baseline = config.baseline_m or scene.baseline
    positions = grid_positions(
        config.frames, np.asarray(scene.camera_center), baseline, offset=False
    )
    shake = Shake(config.shake, config.shake_translation_m, config.seed)
    windows = config.frame_windows()[:, 1:3]
    return Trajectory(positions, np.asarray(scene.target), windows, shake)


class EmulatedCamera(Closing):
    """A DAVIS346 that films a built-in scene: APS frames, DVS events and APS triggers.

    Use as ``with EmulatedCamera("room", seed=1) as camera: for packet in camera: ...``.
    ``camera.truth`` gives the ground truth (see :mod:`davis_io.emulator.truth`).
    Keyword arguments are the fields of :class:`EmulatorConfig`.
    """

    def __init__(self, scene: str = "room", **settings) -> None:
        self.config = EmulatorConfig(scene=scene, **settings)
        self.scene = get_scene(self.config.scene)
        self.trajectory = _build_trajectory(self.config, self.scene)
        self.info = SourceInfo(
            camera="DAVIS346",
            serial="EMULATED",
            width=self.config.width,
            height=self.config.height,
            color_filter=self.config.color_filter,
            origin=f"emulator:{self.config.scene}",
            extra={
                "emulator": {
                    **asdict(self.config),
                    "color_filter": self.config.color_filter.value,
                    "dvs_threshold_on": DVS_PRESETS[self.config.dvs_preset].threshold_on,
                    "dvs_threshold_off": DVS_PRESETS[self.config.dvs_preset].threshold_off,
                }
            },
        )

    @classmethod
    def from_config(cls, config: EmulatorConfig) -> EmulatedCamera:
        """A camera with exactly these settings."""
        return cls(**asdict(config))

    @classmethod
    def of_session(cls, device_config: dict) -> EmulatedCamera:
        """The camera an emulated session was recorded with, from its manifest's device config.

        Raises:
            UsageError: the session was not recorded by the emulator.
        """
        if "emulator" not in device_config:
            raise UsageError(
                "this session was not recorded by the emulator (its device configuration has no "
                "'emulator' settings); record one with seecap record --emulate"
            )
        settings = dict(device_config["emulator"])
        for stated in ("dvs_threshold_on", "dvs_threshold_off"):  # the preset's, written back
            settings.pop(stated, None)
        return cls(**settings)

    @cached_property
    def truth(self) -> Truth:
        """Ground truth of this recording (rendered on first use)."""
        return build_truth(self.config, self.scene, self.trajectory)

    @cached_property
    def _camera(self) -> PinholeCamera:
        return self.config.camera

    @cached_property
    def _channels(self) -> np.ndarray | None:
        return filter_channels(self.config.color_filter, self.config.height, self.config.width)

    @cached_property
    def _weights(self) -> np.ndarray:
        return filter_weights(self.config.color_filter, self.config.height, self.config.width)

    def sensor_image(self, c2w: np.ndarray) -> np.ndarray:
        """``(H, W)`` float32 radiance each pixel sees through its filter at pose ``c2w``."""
        if self._channels is not None:
            return self.scene.render_channel(self._camera, c2w, self._channels)
        radiance, _ = self.scene.render(self._camera, c2w)
        return through_filter(radiance, self._weights)

    def expose_at(
        self,
        times_us: np.ndarray,
        weights: np.ndarray | None = None,
        rng: np.random.Generator | None = None,
    ) -> np.ndarray:
        """``(H, W)`` ADC values of an exposure summed from what the pixels see at ``times_us``.

        Args:
            times_us: sample times of the exposure, µs.
            weights: their integral weights summing to 1, or None for evenly spaced times.
            rng: noise generator, or None for a noise-free frame.
        """
        subframes = np.stack([self.sensor_image(c2w) for c2w in self.trajectory.c2w(times_us)])
        settings = ApsSettings(self.config.response, self.config.gain_per_s)
        return expose(subframes, self.config.exposure_us * 1e-6, settings, rng, weights)

    def _frame(self, window: np.ndarray, rng: np.random.Generator | None) -> Frame:
        times = subframe_times(int(window[1]), int(window[2]), self.config.subframes)
        image = self.expose_at(times, rng=rng)
        return Frame(image, int(window[1]), int(window[2]), int(window[0]), int(window[3]), 10)

    def noise_free_frame(self, frame: Frame) -> np.ndarray:
        """``(H, W)`` ADC values the emulator records for ``frame``'s exposure, without noise."""
        start, end = frame.exposure_start_us, frame.exposure_end_us
        return self.expose_at(subframe_times(start, end, self.config.subframes))

    def _triggers(self, windows: np.ndarray) -> np.ndarray:
        kinds = [
            TriggerKind.APS_FRAME_START,
            TriggerKind.APS_EXPOSURE_START,
            TriggerKind.APS_EXPOSURE_END,
            TriggerKind.APS_FRAME_END,
        ]
        triggers = np.empty(windows.size, TRIGGER_DTYPE)
        triggers["t"] = windows.ravel()
        triggers["kind"] = np.tile(np.array(kinds, np.int8), len(windows))
        return triggers

    def _imu(self) -> np.ndarray:
        if not self.config.imu_rate_hz:
            return empty_imu()
        period_us = 1_000_000 // self.config.imu_rate_hz
        times = np.arange(0, self.config.end_us + 1, period_us, dtype=np.int64)
        return imu_readings(self.trajectory, times)

    def __iter__(self) -> Iterator[Packet]:
        config = self.config
        windows = config.frame_windows()
        triggers, imu = self._triggers(windows), self._imu()
        pixels = DvsPixels(DVS_PRESETS[config.dvs_preset], config.height, config.width, config.seed)
        aps_rng = np.random.default_rng([config.seed, 0xA95]) if config.aps_noise else None
        step_times = np.arange(0, config.end_us + 1, config.dvs_step_us, dtype=np.int64)
        poses = self.trajectory.c2w(step_times)
        next_frame = 0
        for chunk_start in range(0, config.end_us + 1, config.packet_us):
            chunk_end = chunk_start + config.packet_us
            steps = np.flatnonzero((step_times >= chunk_start) & (step_times < chunk_end))
            events = [pixels.step(self.sensor_image(poses[i]), int(step_times[i])) for i in steps]
            frames = []
            while next_frame < len(windows) and windows[next_frame, 3] < chunk_end:
                frames.append(self._frame(windows[next_frame], aps_rng))
                next_frame += 1
            yield Packet(
                events=np.concatenate(events) if events else empty_events(),
                frames=frames,
                imu=_within(imu, chunk_start, chunk_end),
                triggers=_within(triggers, chunk_start, chunk_end),
            )


def _within(records: np.ndarray, start_us: int, end_us: int) -> np.ndarray:
    """The records (sorted by ``t``) with ``start_us <= t < end_us``."""
    first, last = np.searchsorted(records["t"], [start_us, end_us])
    return records[first:last]
