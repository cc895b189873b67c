"""Capture viewpoints, hand-shake motion and the true camera-to-world pose at any time.

Poses are 4x4 camera-to-world matrices with OpenCV camera axes (x right, y down, z forward).
Viewpoints lie on a serpentine grid in a plane facing the scene, all looking at one target, like
a forward-facing (LLFF) capture. The camera rests at each view during its exposure, moves to the
next view between exposures on a minimum-jerk path, and shakes all the time: every rotation and
translation axis follows a sum of three sinusoids with seeded frequencies (1.5..6 Hz) and phases.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.errors import UsageError
from davis_io.types import IMU_DTYPE

__all__ = [
    "Shake",
    "Trajectory",
    "grid_positions",
    "imu_readings",
    "look_at",
    "rotation_from_vector",
]

_DOWN = np.array([0.0, 1.0, 0.0])

STILL_RAMP_US = 100_000
"""How long the shake takes to fade out before a still stretch and back in after it."""


def look_at(positions: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Camera-to-world poses ``(N, 4, 4)`` at ``positions`` ``(N, 3)`` looking at ``target``.

    The camera's y axis points as close to world +y (down) as the viewing direction allows.
    """
    positions = np.atleast_2d(np.asarray(positions, np.float64))
    forward = np.asarray(target, np.float64) - positions
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    right = np.cross(_DOWN, forward)
    right /= np.linalg.norm(right, axis=1, keepdims=True)
    down = np.cross(forward, right)
    poses = np.tile(np.eye(4), (len(positions), 1, 1))
    poses[:, :3, 0], poses[:, :3, 1], poses[:, :3, 2] = right, down, forward
    poses[:, :3, 3] = positions
    return poses


def rotation_from_vector(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` from axis-angle vectors ``(N, 3)`` in radians (Rodrigues)."""
    rotvec = np.atleast_2d(np.asarray(rotvec, np.float64))
    angle = np.linalg.norm(rotvec, axis=1)
    axis = rotvec / np.where(angle > 0, angle, 1)[:, None]
    cross = np.zeros((len(rotvec), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    cross -= cross.transpose(0, 2, 1)
    sin, cos = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + sin * cross + (1 - cos) * (cross @ cross)


def grid_positions(count: int, center: np.ndarray, spacing: float, *, offset: bool) -> np.ndarray:
    """``count`` positions on a serpentine grid in the plane z = center z, ``(count, 3)``.

    The grid has ``ceil(sqrt(count))`` columns, is centred on ``center`` and visits the rows
    alternately left to right and right to left, so neighbours in order are neighbours in space.
    With ``offset`` the grid is shifted by half a spacing on both axes (held-out test views lie
    between training views).
    """
    if count < 0:
        raise UsageError(f"view count {count} must not be negative")
    columns = max(1, int(np.ceil(np.sqrt(count))))
    rows = max(1, int(np.ceil(count / columns)))
    index = np.arange(count)
    row, column = index // columns, index % columns
    column = np.where(row % 2 == 1, columns - 1 - column, column)
    shift = 0.5 if offset else 0.0
    x = (column - (columns - 1) / 2 + shift) * spacing
    y = (row - (rows - 1) / 2 + shift) * spacing * 0.6
    return np.asarray(center, np.float64) + np.stack([x, y, np.zeros(count)], axis=1)


@dataclass(frozen=True)
class Shake:
    """Smooth hand shake: per axis a sum of three sinusoids, in the camera's own frame.

    Attributes:
        rotation_deg: RMS rotation about the camera's x and y axes (roll gets half), degrees.
        translation_m: RMS translation along each camera axis, metres.
        seed: selects frequencies and phases.
    """

    rotation_deg: float
    translation_m: float
    seed: int
    still_us: tuple[int, int] | None = None
    """A stretch ``(start, end)`` in which the hand holds still: the shake fades out over
    :data:`STILL_RAMP_US` before it and back in after it."""

    def _components(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rng = np.random.default_rng([self.seed, 0x5A4E])
        frequency_hz = rng.uniform(1.5, 6.0, size=(6, 3))
        phase = rng.uniform(0, 2 * np.pi, size=(6, 3))
        weight = rng.uniform(0.5, 1.0, size=(6, 3))
        rms = np.sqrt((weight**2).sum(axis=1, keepdims=True) / 2)
        scale = np.array([1.0, 1.0, 0.5, 1.0, 1.0, 1.0])[:, None]
        amplitude = scale * weight / rms
        amplitude[:3] *= np.deg2rad(self.rotation_deg)
        amplitude[3:] *= self.translation_m
        return frequency_hz, phase, amplitude

    def envelope(self, times_us: np.ndarray) -> np.ndarray:
        """The shake's strength ``(N,)`` at ``times_us``: 1, down to 0 in the still stretch."""
        if self.still_us is None:
            return np.ones(len(times_us))
        start, end = self.still_us
        before = np.clip((start - times_us) / STILL_RAMP_US, 0, 1)
        after = np.clip((times_us - end) / STILL_RAMP_US, 0, 1)
        fade = np.maximum(before, after)
        return fade**3 * (10 - 15 * fade + 6 * fade**2)  # minimum jerk: no kick at either end

    def offsets(self, times_us: np.ndarray) -> np.ndarray:
        """Camera-frame motion ``(N, 4, 4)`` at ``times_us``: apply as ``base @ offset``."""
        frequency_hz, phase, amplitude = self._components()
        seconds = np.asarray(times_us, np.float64).reshape(-1, 1, 1) * 1e-6
        signal = (amplitude * np.sin(2 * np.pi * frequency_hz * seconds + phase)).sum(axis=2)
        signal *= self.envelope(np.asarray(times_us, np.float64).ravel())[:, None]
        offsets = np.tile(np.eye(4), (len(signal), 1, 1))
        offsets[:, :3, :3] = rotation_from_vector(signal[:, :3])
        offsets[:, :3, 3] = signal[:, 3:]
        return offsets


@dataclass(frozen=True)
class Trajectory:
    """The true camera path of a recording.

    Attributes:
        positions: ``(F, 3)`` rest position of the camera during each exposure, metres.
        target: point every view looks at.
        exposure_windows_us: ``(F, 2)`` int64 start and end of each exposure.
        shake: hand shake added at every instant.
    """

    positions: np.ndarray
    target: np.ndarray
    exposure_windows_us: np.ndarray
    shake: Shake

    def base_positions(self, times_us: np.ndarray) -> np.ndarray:
        """Positions ``(N, 3)`` without shake: at rest in exposures, minimum jerk in between."""
        times = np.asarray(times_us, np.float64).ravel()
        starts, ends = self.exposure_windows_us[:, 0], self.exposure_windows_us[:, 1]
        before = np.clip(np.searchsorted(ends, times, side="left"), 0, len(ends) - 1)
        previous = np.clip(before - 1, 0, len(ends) - 1)
        gap = np.maximum(starts[before] - ends[previous], 1)
        fraction = np.clip((times - ends[previous]) / gap, 0, 1)
        fraction = np.where(before == previous, 1.0, fraction)
        ease = fraction**3 * (10 - 15 * fraction + 6 * fraction**2)
        return (1 - ease)[:, None] * self.positions[previous] + ease[:, None] * self.positions[
            before
        ]

    def c2w(self, times_us: np.ndarray) -> np.ndarray:
        """True camera-to-world poses ``(N, 4, 4)`` at integer µs times ``(N,)``."""
        times = np.asarray(times_us, np.int64).ravel()
        if len(self.positions) == 0:
            raise UsageError("a trajectory needs at least one view")
        base = (
            look_at(self.base_positions(times), self.target) if len(times) else np.empty((0, 4, 4))
        )
        return base @ self.shake.offsets(times)


_GRAVITY_M_S2 = np.array([0.0, 9.80665, 0.0])  # world +y points down


def imu_readings(trajectory: Trajectory, times_us: np.ndarray) -> np.ndarray:
    """Ideal IMU samples along a trajectory, with the IMU's axes equal to the camera's.

    Angular rate is the camera-frame rotation rate from central differences over ±0.5 ms;
    acceleration is the specific force (acceleration minus gravity, world +y down) in the
    camera frame, from second differences over ±1 ms, in g. Temperature is a constant 30 °C.

    Returns:
        An ``IMU_DTYPE`` array, one sample per time.
    """
    times = np.asarray(times_us, np.int64)
    samples = np.empty(len(times), IMU_DTYPE)
    samples["t"] = times
    if len(times) == 0:
        return samples
    before, after = trajectory.c2w(times - 500), trajectory.c2w(times + 500)
    relative = np.einsum("nji,njk->nik", before[:, :3, :3], after[:, :3, :3])
    skew = (relative - relative.transpose(0, 2, 1)) / 2
    rate = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], 1) / 1e-3
    centre = trajectory.c2w(times)
    earlier, later = trajectory.c2w(times - 1000), trajectory.c2w(times + 1000)
    acceleration = (later[:, :3, 3] - 2 * centre[:, :3, 3] + earlier[:, :3, 3]) / 1e-6
    force = np.einsum("nji,nj->ni", centre[:, :3, :3], acceleration - _GRAVITY_M_S2)
    samples["gyro_dps"] = np.rad2deg(rate)
    samples["acc_g"] = force / 9.80665
    samples["temperature_c"] = 30.0
    return samples
