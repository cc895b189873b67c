"""``EmulatorConfig``: every setting of an emulated recording (same settings, same bytes)."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, replace

import numpy as np

from davis_io.chips import COLOUR_MODELS, DEFAULT_FRAME_GAP_US, DEFAULT_MODEL, SENSOR_SIZES
from davis_io.emulator.dvs import DVS_PRESETS
from davis_io.emulator.lens_view import lens_distortion
from davis_io.emulator.raytrace import PinholeCamera
from davis_io.emulator.response import RESPONSE_CURVES
from davis_io.emulator.sensor import SENSOR_KINDS, Sensor, default_sensor, draw_sensor
from davis_io.errors import UsageError
from davis_io.lens import Lens
from davis_io.types import ColorFilter

__all__ = ["EmulatorConfig", "model_settings"]

_TRUTH_BYTES_PER_PIXEL = 3 * 4 * 8
"""Memory per pixel of a view's truth and its renders while it is made: linear RGB (float32)
and depth, the bracket of LDR images, the sub-frame renders of one exposure."""


def _check_model(model: str) -> None:
    """Raises UsageError: ``model`` is not a camera model the emulator knows."""
    if model not in SENSOR_SIZES:
        raise UsageError(f"camera model {model!r} is not one of {', '.join(SENSOR_SIZES)}")


def model_settings(model: str) -> dict:
    """The :class:`EmulatorConfig` fields that film with ``model``'s whole array.

    Its size, and mono where the model was made mono only.

    Raises:
        UsageError: an unknown model.
    """
    _check_model(model)
    width, height = SENSOR_SIZES[model]
    settings = {"model": model, "width": width, "height": height}
    if model not in COLOUR_MODELS:
        settings["color_filter"] = ColorFilter.MONO
    return settings


@dataclass(frozen=True)
class EmulatorConfig:
    """Everything that defines an emulated recording; the same config gives the same bytes.

    Attributes:
        scene: built-in scene name (``room``, ``lamp``, ``corridor``).
        frames: number of training frames (views).
        test_views: number of held-out views in the truth.
        exposure_us: APS exposure of every frame, µs (see ``exposure_steps``).
        frame_interval_us: SOF to SOF, µs; 0 means ``exposure_us`` + the default gap (50 ms).
        readout_us: reset read before and signal read after each exposure, µs.
        lead_us: device time before the first frame's readout, µs.
        subframes: renders per exposure for the APS integral (trapezoid weights).
        dvs_step_us: time between DVS samples, µs.
        sensor: ``default`` (the next three settings name the sensor) or ``random`` (drawn from
            ``seed``: :mod:`davis_io.emulator.sensor`).
        dvs_preset: DVS pixel preset (``clean``, ``noisy``, ``v2e-clean``, ``v2e-noisy``).
        response: APS response curve (``reinhard_gamma``, ``film``, ``linear``, ``s_curve``).
        color_filter: colour filter of APS and DVS pixels (mono on a model made mono only; a
            random sensor of such a model is drawn mono too).
        aps_noise: add shot and read noise to frames.
        gain_exposure_us: exposure whose reciprocal is the sensor gain, µs (0: ``exposure_us``,
            which keeps every exposure equally bright; another value makes an exposure bracket:
            shorter is darker, longer clips).
        noise_scale: multiplier of the DVS leak and shot-noise rates.
        model: the camera model the recording states (a key of
            :data:`~davis_io.chips.SENSOR_SIZES`).
        width: sensor columns: the model's, or fewer (a region of interest).
        height: sensor rows: the model's, or fewer.
        focal_px: focal length in pixels (principal point at the image centre).
        shake: RMS hand-shake rotation, degrees.
        shake_translation_m: RMS hand-shake translation, metres.
        baseline_m: spacing of capture positions, metres; 0 takes the scene's own.
        seed: seeds the shake, the pixel mismatch and all noise.
        packet_us: device time per packet, µs.
        imu_rate_hz: IMU samples per second (ideal gyro and accelerometer, camera axes); 0 for
            none.
        event_window_us: keep only the events within this many µs of an exposure (a recording
            made view by view, or a stream with long gaps); 0 keeps every event.
        still_frames: this many frames in the middle of the recording are taken with the camera
            held still at one place (no move, no shake: only the pixels' noise fires); 0 for
            none.
        lens: ``pinhole``, ``random`` (a radial and tangential distortion drawn from ``seed``)
            or OpenCV's coefficients ``k1,k2,p1,p2[,k3]``.
        exposure_steps: frame ``k`` is exposed for ``exposure_us`` times the ``k``-th of these
            shares in turn, as a camera's auto-exposure sets it (empty: every frame for
            ``exposure_us``); the gain stays that of ``exposure_us``, so a shorter exposure is
            darker.
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
    sensor: str = "default"
    dvs_preset: str = "noisy"
    response: str = "reinhard_gamma"
    color_filter: ColorFilter = ColorFilter.RGGB
    aps_noise: bool = True
    gain_exposure_us: int = 0
    noise_scale: float = 1.0
    model: str = DEFAULT_MODEL
    width: int = SENSOR_SIZES[DEFAULT_MODEL][0]
    height: int = SENSOR_SIZES[DEFAULT_MODEL][1]
    focal_px: float = 280.0
    shake: float = 0.8
    shake_translation_m: float = 0.002
    baseline_m: float = 0.0
    seed: int = 0
    packet_us: int = 10_000
    imu_rate_hz: int = 1000
    event_window_us: int = 0
    still_frames: int = 0
    lens: str = "pinhole"
    exposure_steps: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "exposure_steps", tuple(float(f) for f in self.exposure_steps))
        try:
            object.__setattr__(self, "color_filter", ColorFilter(self.color_filter))
        except ValueError:
            names = ", ".join(f.value for f in ColorFilter)
            raise UsageError(f"colour filter {self.color_filter!r} is not one of {names}") from None
        if self.frame_interval_us == 0:
            object.__setattr__(self, "frame_interval_us", self.exposure_us + DEFAULT_FRAME_GAP_US)
        _check_model(self.model)
        problems = []
        if self.width < 2 or self.height < 2 or self.focal_px <= 0:
            problems.append("width and height of at least 2 pixels and a positive focal length")
        columns, rows = SENSOR_SIZES[self.model]
        if self.width > columns or self.height > rows:
            problems.append(f"a {self.model} has {columns}x{rows} pixels at most")
        if self.model not in COLOUR_MODELS and self.color_filter.is_color:
            problems.append(f"a {self.model} is mono: no colour filter")
        if self.shake < 0 or self.shake_translation_m < 0 or self.baseline_m < 0:
            problems.append("shake, shake translation and baseline must not be negative")
        if self.frames < 1 or self.test_views < 0 or self.subframes < 2:
            problems.append("frames >= 1, test_views >= 0 and subframes >= 2 are needed")
        if self.gain_exposure_us < 0 or self.noise_scale < 0:
            problems.append("gain exposure and noise scale must not be negative")
        if min(self.exposure_us, self.readout_us, self.dvs_step_us, self.packet_us) <= 0:
            problems.append("exposure, readout, DVS step and packet durations must be positive")
        if any(not 0 < factor <= 1 for factor in self.exposure_steps):
            problems.append("exposure steps are shares of the exposure in (0, 1]")
        if self.event_window_us < 0 or not 0 <= self.still_frames <= max(self.frames - 2, 0):
            problems.append(
                "the event window must not be negative, and still frames leave at least one "
                "moving frame on either side"
            )
        if not 0 <= self.imu_rate_hz <= 1_000_000:
            problems.append(f"IMU rate {self.imu_rate_hz} Hz must be within 0..1000000")
        shortest_us = self.exposure_us + 2 * self.readout_us + self.dvs_step_us
        if self.frame_interval_us < shortest_us:
            problems.append(
                f"frame interval {self.frame_interval_us} µs is shorter than exposure + two "
                f"readouts + one DVS step ({shortest_us} µs)"
            )
        if self.sensor not in SENSOR_KINDS:
            problems.append(f"sensor {self.sensor!r} is not one of {', '.join(SENSOR_KINDS)}")
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
        self.distortion  # noqa: B018 -- a lens that cannot be read is refused here
        self._check_memory()

    def _check_memory(self) -> None:
        """Refuse settings whose truth would not fit in half of this machine's memory."""
        per_view = self.width * self.height * _TRUTH_BYTES_PER_PIXEL
        needed = (self.frames + self.test_views) * per_view
        available = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2
        if needed > available:
            raise UsageError(
                f"emulating {self.frames} frames and {self.test_views} test views of "
                f"{self.width}x{self.height} keeps their truth in memory: about "
                f"{needed / 2**30:.1f} GiB, more than half of this machine's "
                f"{2 * available / 2**30:.0f} GiB; emulate at most "
                f"{max(available // per_view - self.test_views, 1)} frames here"
            )

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
    def distortion(self) -> tuple[float, ...]:
        """OpenCV's coefficients of the lens these settings name (empty for a pinhole)."""
        return lens_distortion(self.lens, self.seed)

    @property
    def optics(self) -> Lens:
        """The camera's lens: its pinhole intrinsics and its distortion."""
        return Lens.pinhole(self.width, self.height, self.camera.intrinsics).with_distortion(
            self.distortion
        )

    @property
    def sensor_model(self) -> Sensor:
        """The sensor these settings name, or the one drawn from the seed."""
        if self.sensor == "random":
            sensor = draw_sensor(self.seed)
            if self.model not in COLOUR_MODELS:
                sensor = replace(sensor, color_filter=ColorFilter.MONO)
        else:
            sensor = default_sensor(self.dvs_preset, self.response, self.color_filter)
        return sensor.with_noise_scaled(self.noise_scale)

    @property
    def gain_per_s(self) -> float:
        """Sensor gain, 1 / s: the response's input is gain x radiance x exposure_s."""
        return 1e6 / (self.gain_exposure_us or self.exposure_us)

    def frame_exposures_us(self) -> np.ndarray:
        """``(F,)`` int64 each frame's exposure, µs (:attr:`exposure_steps`' shares in turn)."""
        steps = np.asarray(self.exposure_steps or (1.0,))
        shares = steps[np.arange(self.frames) % len(steps)]
        return np.maximum(np.round(self.exposure_us * shares), 1).astype(np.int64)

    def frame_windows(self) -> np.ndarray:
        """``(F, 4)`` int64 readout start, exposure start, exposure end, readout end, µs."""
        start = self.lead_us + np.arange(self.frames, dtype=np.int64) * self.frame_interval_us
        exposure_start = start + self.readout_us
        exposure_end = exposure_start + self.frame_exposures_us()
        return np.stack([start, exposure_start, exposure_end, exposure_end + self.readout_us], 1)

    @property
    def still_range(self) -> range:
        """The frames taken with the camera held still (empty without ``still_frames``)."""
        first = (self.frames - self.still_frames) // 2
        return range(first, first + self.still_frames)

    def still_us(self) -> tuple[int, int] | None:
        """From the end of the exposure before the still frames to the end of the last one."""
        if not self.still_frames:
            return None
        windows = self.frame_windows()
        still = self.still_range
        return int(windows[still.start - 1, 2]), int(windows[still.stop - 1, 2])

    def event_kept(self, times_us: np.ndarray) -> np.ndarray:
        """Which events ``(N,)`` the recording keeps: all, or those near an exposure."""
        if not self.event_window_us:
            return np.ones(len(times_us), dtype=bool)
        windows = self.frame_windows()
        starts = windows[:, 1] - self.event_window_us
        ends = windows[:, 2] + self.event_window_us
        index = np.searchsorted(starts, times_us, side="right") - 1
        return (index >= 0) & (times_us <= ends[np.maximum(index, 0)])

    @property
    def end_us(self) -> int:
        """Device time of the last DVS sample, µs."""
        return int(self.frame_windows()[-1, 3]) + self.lead_us

    def to_json(self) -> dict:
        """JSON-safe settings (:meth:`from_json` makes the same config again)."""
        return {
            **asdict(self),
            "color_filter": self.color_filter.value,
            "exposure_steps": list(self.exposure_steps),
        }

    @classmethod
    def from_json(cls, data: dict) -> EmulatorConfig:
        """Inverse of :meth:`to_json`."""
        return cls(**data)
