"""Making a session ready to fit: the sensor measured, then the poses estimated, when missing."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from davis_io.calibration.session_calibration import session_calibration
from davis_io.cores import cores_limited
from davis_io.lens import read_camera_calibration
from davis_io.poses.estimate import estimate_poses, made_with
from davis_io.poses.recovery import matched_pair_count
from davis_io.session import Session

__all__ = [
    "PreparationEstimate",
    "StageLines",
    "estimate_preparation",
    "preparation_seconds",
    "prepare_session",
]

CALIBRATION_S_PER_MILLION_EVENTS = 0.8
"""The calibration's seconds per million events on 2 cores (``seecap calibrate``, the whole
process): 15.3 s for 18.5 M events (an emulated room) and 17.6 s for 24.7 M (a bright lamp)."""
POSES_S_PER_PAIR = 0.012
"""Matching's seconds per pair of latent frames, on one thread: 24-39 s for 3,160 pairs (every
pair of 80 latent frames)."""
POSES_S_PER_IMAGE = 0.45
"""Seconds per latent frame of the rest of the pose stage (EDI, features, the lens, and mapping's
part that grows with the frames alone)."""
POSES_S_PER_IMAGE_SQUARED = 0.0015
"""Mapping's seconds per latent frame squared: every global adjustment covers the whole model so
far. With :data:`POSES_S_PER_IMAGE`, the rest of the pose stage measured 45-51 s for 80 latent
frames (16 frames at b = 4), 140 s for 200 (40 frames) and 607 s for 500 (100 frames); the two
terms give 46, 150 and 600 s. A single rate of 0.65 s gave 52, 130 and 325 s."""


def prepare_session(
    session_dir: Path | str,
    b: int,
    log: Callable[[str], None] = print,
    camera_calibration: Path | None = None,
    threads: int = 0,
) -> float:
    """Calibrate the sensor and estimate poses for ``b`` if the session lacks them.

    Args:
        session_dir: the session folder.
        b: bins per exposure of the poses.
        log: receives one line per step taken.
        camera_calibration: a calibration file of the camera's lens (read by
            :func:`davis_io.lens.read_camera_calibration`); poses made with another lens are
            estimated again with this one, held fixed.
        threads: the cores the calibration's and COLMAP's thread pools may use (0: all).

    Returns:
        The seconds spent.

    Raises:
        ColmapError: the poses could not be estimated (with advice).
        SessionError, UsageError: the session cannot be read or written.
    """
    start = time.perf_counter()
    with cores_limited(threads), Session.open(session_dir) as session:
        lens = None
        if camera_calibration is not None:
            lens = read_camera_calibration(camera_calibration, session.width, session.height)
        assumed_us = session.manifest.exposure_assumed_us
        if assumed_us is not None:
            log(
                f"exposures assumed: the recording's frames state none, so each was given "
                f"{assumed_us / 1000:.1f} ms (median) when recorded (`seecap inspect` says so; "
                "record again with --exposure to give the real one)"
            )
        if session.calibration() is None:
            log("measuring the sensor from the recording")
            calibration = session_calibration(session, progress=log)
            log(calibration.summary())
            log(f"sensor measured in {time.perf_counter() - start:.0f} s")
        poses = session.poses(b)
        if poses is None or (lens is not None and not made_with(poses, lens)):
            log(f"estimating poses (b={b})" + (f" with the lens {lens.summary()}" if lens else ""))
            begun = time.perf_counter()
            report = estimate_poses(session, b=b, lens=lens, progress=StageLines(log))
            log(report.summary())
            log(f"poses estimated in {time.perf_counter() - begun:.0f} s")
    return time.perf_counter() - start


@dataclass(frozen=True)
class PreparationEstimate:
    """What :func:`prepare_session` will take, estimated from the session's size before it starts.

    Attributes:
        calibration_s: seconds to measure the sensor (0 when stored).
        poses_s: seconds to estimate the poses (0 when stored; a doubtful calibration, which
            makes COLMAP reconstruct twice, is not foreseen).
        events: events of the recording.
        latent_frames: latent frames the poses would be estimated for.
    """

    calibration_s: float
    poses_s: float
    events: int
    latent_frames: int

    @property
    def total_s(self) -> float:
        """Seconds of both steps."""
        return self.calibration_s + self.poses_s

    def summary(self) -> str:
        """One line: what each step to come should take and what it is estimated from."""
        steps = []
        if self.calibration_s:
            steps.append(
                f"about {self.calibration_s:.0f} s to measure the sensor "
                f"({self.events / 1e6:.1f} M events)"
            )
        if self.poses_s:
            steps.append(f"{self.poses_s:.0f} s for poses ({self.latent_frames} latent frames)")
        if not steps:
            return "the sensor and poses are stored"
        return " and ".join(steps)


def preparation_seconds(
    events: int, views: int, per_view: int, *, calibrated: bool, posed: bool
) -> PreparationEstimate:
    """:class:`PreparationEstimate` from the session's counts and what it already holds.

    ``views`` frames of ``per_view`` latent frames each (b + 1).
    """
    latent_frames = views * per_view
    pairs = matched_pair_count(views, per_view)
    return PreparationEstimate(
        calibration_s=0.0 if calibrated else CALIBRATION_S_PER_MILLION_EVENTS * events / 1e6,
        poses_s=0.0
        if posed
        else POSES_S_PER_PAIR * pairs
        + POSES_S_PER_IMAGE * latent_frames
        + POSES_S_PER_IMAGE_SQUARED * latent_frames**2,
        events=events,
        latent_frames=latent_frames,
    )


def estimate_preparation(session_dir: Path | str, b: int) -> PreparationEstimate:
    """What :func:`prepare_session` with ``b`` bins will take on this session.

    Raises:
        SessionError: the session cannot be read.
    """
    with Session.open(session_dir) as session:
        return preparation_seconds(
            session.event_count,
            session.frame_count,
            b + 1,
            calibrated=session.calibration() is not None,
            posed=session.poses(b) is not None,
        )


class StageLines:
    """Progress of the pose steps as log lines.

    Each stage as it starts, and a counted one at each quarter of its count with the time taken
    and the time left at that pace.

    Args:
        log: receives each line.
        clock: seconds, monotonic (a test's own clock).
    """

    def __init__(self, log: Callable[[str], None], clock: Callable[[], float] = time.perf_counter):
        self.log, self.clock = log, clock
        self.stage: str | None = None
        self.started = 0.0
        self.quarter = 1

    def __call__(self, stage: str, done: int, total: int) -> None:
        """Report that ``done`` of ``total`` (0: not counted) of ``stage`` are done."""
        now = self.clock()
        if stage != self.stage:
            self.stage, self.started, self.quarter = stage, now, 1
            self.log(f"poses: {stage}")
        if total and done > 0 and 4 * done >= self.quarter * total:
            spent = now - self.started
            left = spent * (total - done) / done
            self.log(f"poses: {stage} {done}/{total} in {spent:.0f} s, about {left:.0f} s left")
            self.quarter = 4 * done // total + 1
