"""Calibrating a recorded session: read its frames and events, measure, store ``/calibration``."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from davis_io.calibration.estimate import (
    LATENCIES_US,
    LONGER_LATENCIES_US,
    CalibrationInput,
    Progress,
    calibrate_frames,
)
from davis_io.errors import UsageError
from davis_io.session import (
    DEFAULT_THRESHOLD,
    SensorCalibration,
    Session,
    default_calibration,
    writer_lock,
)

__all__ = ["calibrate_session", "session_calibration"]

LATEST_US = max(LATENCIES_US + LONGER_LATENCIES_US)
"""How far past the last exposure the events are read: the latest latency the profile tries."""


def _recording(session: Session) -> CalibrationInput:
    table = session.frames_table()
    usable = np.flatnonzero(~np.asarray(table.events_lost, bool))
    frames = [session.frame(int(i)) for i in usable]
    top = float(2 ** frames[0].bit_depth - 1) if frames else 1.0
    start, end = table.exposure_start_us[usable], table.exposure_end_us[usable]
    events = (
        session.events_between(int(start[0]), int(end[-1]) + LATEST_US)
        if len(usable)
        else np.zeros(0, [("t", "i8"), ("x", "u2"), ("y", "u2"), ("p", "i1")])
    )
    return CalibrationInput(
        frames=np.stack([f.image for f in frames]).astype(np.float64) / top
        if frames
        else np.zeros((0, session.height, session.width)),
        adc_step=1.0 / top,
        times_us=np.ascontiguousarray(events["t"]),
        x=np.ascontiguousarray(events["x"]),
        y=np.ascontiguousarray(events["y"]),
        is_on=events["p"] > 0,
        exposure_start_us=start,
        exposure_end_us=end,
        gaps_us=session.event_gaps(),
    )


def calibrate_session(
    session: Session | Path | str, *, force: bool = False, progress: Progress | None = None
) -> SensorCalibration:
    """Measure the sensor of a session and store it; a stored calibration is reused.

    Frames whose exposure lost events are left out.

    Raises:
        UsageError: too few usable frames or pixels to measure anything.
        SessionError: the session cannot be read or written.
    """
    if not isinstance(session, Session):
        with Session.open(session) as opened:
            return calibrate_session(opened, force=force, progress=progress)
    with writer_lock(session.folder, "measuring the sensor"):
        stored = session.calibration()
        if stored is not None and not force:
            return stored
        session.require_writable()
        calibration = calibrate_frames(_recording(session), progress=progress)
        session.write_calibration(calibration)
    return calibration


def session_calibration(session: Session, progress: Progress | None = None) -> SensorCalibration:
    """The stored calibration, measured first when there is none.

    A recording that cannot be measured (fewer than two frames) gets the nominal sensor
    (:data:`~davis_io.session.DEFAULT_THRESHOLD`), stored with the reason; one whose values
    were measured only in part says which were assumed. Both warn through ``progress``.
    """
    stored = session.calibration()
    if stored is not None:
        return stored
    try:
        calibration = calibrate_session(session, progress=progress)
    except UsageError as error:
        fallback = default_calibration(DEFAULT_THRESHOLD, f"not measured: {error}")
        (progress or warnings.warn)(
            f"the sensor could not be measured ({error}); using the nominal threshold "
            f"{DEFAULT_THRESHOLD}"
        )
        session.write_calibration(fallback)
        return fallback
    if calibration.assumed:
        (progress or warnings.warn)(
            f"the sensor could not be measured in full: assumed {', '.join(calibration.assumed)} "
            f"(`seecap inspect {session.folder}` says why and what stands in for each)"
        )
    return calibration
