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
from functools import cached_property
from pathlib import Path

import numpy as np

from davis_io.colorfilter import filter_channels, filter_weights
from davis_io.emulator.aps import ApsSettings, expose, subframe_times
from davis_io.emulator.colorfilter import through_filter
from davis_io.emulator.config import EmulatorConfig
from davis_io.emulator.dvs import DvsPixels
from davis_io.emulator.lens_view import LensView
from davis_io.emulator.scene import Scene
from davis_io.emulator.scenes import get_scene
from davis_io.emulator.trajectory import Shake, Trajectory, grid_positions, imu_readings
from davis_io.emulator.truth import build_truth
from davis_io.errors import UsageError
from davis_io.session.truth import TRUTH_DIR, Truth, load_truth, save_truth
from davis_io.types import (
    TRIGGER_DTYPE,
    Closing,
    Frame,
    Packet,
    SourceInfo,
    TriggerKind,
    empty_events,
    empty_imu,
)

__all__ = ["EmulatedCamera"]


def _build_trajectory(config: EmulatorConfig, scene: Scene) -> Trajectory:
    """The true camera path of a recording with these settings."""
    baseline = config.baseline_m or scene.baseline
    moving = config.frames - config.still_frames
    positions = grid_positions(moving, np.asarray(scene.camera_center), baseline, offset=False)
    still = config.still_range
    if config.still_frames:  # held still where the frame before the stretch was taken
        held = np.repeat(positions[still.start - 1 : still.start], config.still_frames, axis=0)
        positions = np.concatenate([positions[: still.start], held, positions[still.start :]])
    shake = Shake(config.shake, config.shake_translation_m, config.seed, config.still_us())
    windows = config.frame_windows()[:, 1:3]
    return Trajectory(positions, np.asarray(scene.target), windows, shake)


class EmulatedCamera(Closing):
    """A DAVIS346 (or DAVIS240) that films a built-in scene: APS frames, DVS events, triggers.

    Use as ``with EmulatedCamera("room", seed=1) as camera: for packet in camera: ...``.
    ``camera.truth`` gives the ground truth (format: :mod:`davis_io.session.truth`) and
    ``camera.write_truth(session_folder)`` stores it beside a recording.
    Keyword arguments are the fields of :class:`EmulatorConfig`.
    """

    def __init__(self, scene: str = "room", **settings) -> None:
        self.config = EmulatorConfig(scene=scene, **settings)
        self.sensor = self.config.sensor_model
        self.scene = get_scene(self.config.scene)
        self.trajectory = _build_trajectory(self.config, self.scene)
        aps = {"exposure_us": self.config.exposure_us}
        aps["frame_interval_us"] = self.config.frame_interval_us
        self.info = SourceInfo(
            camera=self.config.model,
            serial="EMULATED",
            width=self.config.width,
            height=self.config.height,
            color_filter=self.sensor.color_filter,
            origin=f"emulator:{self.config.scene}",
            extra={"config": {"aps": aps, "imu": {"rate_hz": self.config.imu_rate_hz}}},
        )

    @classmethod
    def from_config(cls, config: EmulatorConfig) -> EmulatedCamera:
        """A camera with exactly these settings."""
        return cls(**config.to_json())

    @classmethod
    def of_session(cls, session_dir) -> EmulatedCamera:
        """The camera an emulated session was recorded with, from its ``truth/``.

        Raises:
            UsageError: the session has no truth of the emulator's.
            SessionError: its truth cannot be read.
        """
        camera = load_truth(session_dir).camera
        if not camera:
            raise UsageError(
                f"{session_dir}: its truth does not say how it was recorded; record it again "
                "with seecap record --emulate"
            )
        return cls(**camera)

    @cached_property
    def truth(self) -> Truth:
        """Ground truth of this recording (rendered on first use)."""
        return build_truth(self.config, self.sensor, self.scene, self.trajectory, self._pixels())

    def write_truth(self, session_folder: Path) -> Path:
        """Write this recording's truth into ``session_folder/truth/``; return that folder."""
        return save_truth(self.truth, Path(session_folder) / TRUTH_DIR)

    def _pixels(self) -> DvsPixels:
        """A fresh DVS pixel array of this camera (the same mismatch and noise every time)."""
        config = self.config
        return DvsPixels(self.sensor.dvs, config.height, config.width, config.seed)

    @cached_property
    def _view(self) -> LensView:
        return LensView(self.config.optics)

    @cached_property
    def _channels(self) -> np.ndarray | None:
        return filter_channels(self.sensor.color_filter, self.config.height, self.config.width)

    @cached_property
    def _weights(self) -> np.ndarray:
        return filter_weights(self.sensor.color_filter, self.config.height, self.config.width)

    def sensor_image(self, c2w: np.ndarray) -> np.ndarray:
        """``(H, W)`` float32 radiance each pixel sees through its filter at pose ``c2w``."""
        if self._channels is not None and self._view.lens.is_pinhole:
            return self.scene.render_channel(self._view.camera, c2w, self._channels)
        radiance, _ = self._view.render(self.scene, c2w)
        return through_filter(radiance, self._weights)

    def expose_at(
        self,
        times_us: np.ndarray,
        weights: np.ndarray | None = None,
        rng: np.random.Generator | None = None,
    ) -> np.ndarray:
        """``(H, W)`` ADC values of an exposure summed from what the pixels see at ``times_us``.

        Args:
            times_us: sample times of the exposure, µs, from its start to its end.
            weights: their integral weights summing to 1, or None for evenly spaced times.
            rng: noise generator, or None for a noise-free frame.
        """
        subframes = np.stack([self.sensor_image(c2w) for c2w in self.trajectory.c2w(times_us)])
        settings = ApsSettings(self.sensor.response, self.config.gain_per_s)
        exposure_s = float(times_us[-1] - times_us[0]) * 1e-6
        return expose(subframes, exposure_s, settings, rng, weights)

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
        pixels = self._pixels()
        aps_rng = np.random.default_rng([config.seed, 0xA95]) if config.aps_noise else None
        step_times = np.arange(0, config.end_us + 1, config.dvs_step_us, dtype=np.int64)
        poses = self.trajectory.c2w(step_times - self.sensor.latency_us)
        next_frame = 0
        for chunk_start in range(0, config.end_us + 1, config.packet_us):
            chunk_end = chunk_start + config.packet_us
            steps = np.flatnonzero((step_times >= chunk_start) & (step_times < chunk_end))
            events = [pixels.step(self.sensor_image(poses[i]), int(step_times[i])) for i in steps]
            events = np.concatenate(events) if events else empty_events()
            frames = []
            while next_frame < len(windows) and windows[next_frame, 3] < chunk_end:
                frames.append(self._frame(windows[next_frame], aps_rng))
                next_frame += 1
            yield Packet(
                events=events[config.event_kept(events["t"])],
                frames=frames,
                imu=_within(imu, chunk_start, chunk_end),
                triggers=_within(triggers, chunk_start, chunk_end),
            )


def _within(records: np.ndarray, start_us: int, end_us: int) -> np.ndarray:
    """The records (sorted by ``t``) with ``start_us <= t < end_us``."""
    first, last = np.searchsorted(records["t"], [start_us, end_us])
    return records[first:last]
