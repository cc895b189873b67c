"""Reads a recorded session (and its truth, when emulated) into :class:`TrainingData`."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from davis_io.geometry import interpolate_poses
from davis_io.session import SensorCalibration, Session, SessionPoses, Truth, contrast_bins
from seenerf.data.arrays import TestViews, TrainingData, TrainTruth, pixel_layout
from seenerf.errors import TrainingDataError

__all__ = ["load_training_data"]


def _calibration(
    session: Session, sensor_from_truth: bool, threshold: float | None
) -> SensorCalibration:
    """The sensor values a fit uses: measured (or the truth's), a stated threshold over both."""
    if sensor_from_truth:
        truth = session.truth()
        if truth is None:
            raise TrainingDataError(
                f"{session.folder}: the sensor's true values need an emulated session's truth/"
            )
        calibration = truth.sensor_calibration()
    else:
        calibration = session.calibration()
        if calibration is None:
            raise TrainingDataError(
                f"{session.folder}: the sensor is not calibrated yet; run `seecap calibrate "
                f"{session.folder}` (seecap fit runs it when missing)"
            )
    return calibration if threshold is None else calibration.with_threshold(threshold)


def _poses_at(poses: SessionPoses, stored_times: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The poses at other latent time points (the calibration's event latency moves them)."""
    known_times = (poses.time_us if poses.time_us is not None else stored_times).reshape(-1)
    if np.array_equal(known_times, times.reshape(-1)):
        return poses.c2w
    order = np.argsort(known_times, kind="stable")
    unique = np.concatenate([[True], np.diff(known_times[order]) > 0])
    known_c2w = poses.c2w.reshape(-1, 4, 4)[order][unique]
    moved = interpolate_poses(known_times[order][unique], known_c2w, times.reshape(-1))
    return moved.reshape(*times.shape, 4, 4)


def load_training_data(
    session_dir: Path | str,
    b: int,
    *,
    sensor_from_truth: bool = False,
    threshold: float | None = None,
    keep_lost: bool = False,
) -> TrainingData:
    """Frames, event bins and poses of a session as float32 training arrays.

    The bins are the session's events in light time, weighted by their pixels' calibrated
    thresholds (:func:`~davis_io.session.contrast_bins`), in units of the mean
    threshold, with each frame's lead from the start of its stretch of the stream; the poses
    are moved to their latent time points.

    Args:
        session_dir: the session folder (calibrated, with poses for ``b``).
        b: event bins per exposure.
        sensor_from_truth: use the emulated sensor's true values instead of the measured ones
            (the white-box fit).
        threshold: a contrast threshold stated for ON, OFF and every pixel (None: calibrated).
        keep_lost: also train on frames whose exposure window lost events.

    Raises:
        TrainingDataError: no calibration or no poses for ``b`` yet, or no usable frame.
    """
    with Session.open(session_dir) as session:
        poses = session.poses(b)
        if poses is None:
            raise TrainingDataError(
                f"{session_dir}: no poses for b={b}; run `seecap poses {session_dir} --bins {b}` "
                "(seecap fit runs it when missing)"
            )
        calibration = _calibration(session, sensor_from_truth, threshold)
        table = session.frames_table()
        bins = contrast_bins(session, b, calibration, settled=True)
        c2w = _poses_at(poses, session.bins(b).split_us, bins.split_us)
        usable = np.flatnonzero(keep_lost | ~np.asarray(table.events_lost, bool))
        if len(usable) == 0 and len(table.events_lost):
            warnings.warn(
                f"{session_dir}: every frame's exposure lost events (drops, or gaps in the "
                "stream): fitting them all, their events as recorded",
                stacklevel=2,
            )
            usable = np.arange(len(table.events_lost))
        if len(usable) == 0:
            raise TrainingDataError(f"{session_dir}: the session holds no frame to fit")
        frames = [session.frame(int(i)) for i in usable]
        scale = float(2 ** frames[0].bit_depth - 1)
        ldr = np.stack([f.image for f in frames]).astype(np.float32) / scale
        mix, channel = pixel_layout(session.color_filter, session.height, session.width)
        data = TrainingData(
            ldr=np.clip(ldr, 0.0, 1.0),
            exposure_s=(table.exposure_us[usable] * 1e-6).astype(np.float32),
            weights=bins.weights[usable].astype(np.float32),
            bins=(bins.calibrated[usable] / calibration.threshold).astype(np.float32),
            bins_raw=bins.raw[usable].astype(np.float32),
            c2w=c2w[usable].astype(np.float32),
            intrinsics=poses.intrinsics.astype(np.float32),
            distortion=np.asarray(poses.distortion, np.float32),
            bounds=poses.bounds.astype(np.float32),
            mix=mix,
            channel=channel,
            settled=bins.settled[usable],
            lead=(bins.lead[usable] / calibration.threshold).astype(np.float32),
            stretch=bins.stretch[usable],
            monochrome=not session.color_filter.is_color,
            threshold=calibration.threshold,
            cutoff_hz=calibration.cutoff_hz,
            dead_time_s=calibration.dead_time_us * 1e-6,
            polarity_scale=(
                calibration.threshold_on / calibration.threshold,
                calibration.threshold_off / calibration.threshold,
            ),
            thresholds_measured=calibration.thresholds_measured,
            linear_levels=(calibration.black_level, calibration.saturation)
            if calibration.response_linear
            else None,
            clip_level=calibration.saturation,
            noise_offset=calibration.noise_offset if calibration.response_linear else 0.0,
        )
        truth = session.truth()
        if truth is not None:
            _attach_truth(data, truth, usable, bins.split_us[usable])
    return data.validate()


def _attach_truth(
    data: TrainingData, truth: Truth, usable: np.ndarray, split_us: np.ndarray
) -> None:
    middle = truth.train_c2w.shape[1] // 2
    times = truth.train_time_us[usable].reshape(-1)
    order = np.argsort(times, kind="stable")
    unique = np.concatenate([[True], np.diff(times[order]) > 0])
    known_times = times[order][unique]
    known_c2w = truth.train_c2w[usable].reshape(-1, 4, 4)[order][unique]
    latent = interpolate_poses(known_times, known_c2w, split_us.reshape(-1))
    data.truth = TrainTruth(
        c2w=truth.train_c2w[usable, middle : middle + 1].astype(np.float32),
        sharp_hdr=truth.train_sharp_hdr[usable][:, None].astype(np.float32),
        crf_log_exposure=np.asarray(truth.crf_log_exposure, np.float64),
        crf_value=np.repeat(np.asarray(truth.crf_value, np.float64)[:, None], 3, axis=1),
        latent_c2w=latent.reshape(*split_us.shape, 4, 4).astype(np.float32),
    )
    data.test = TestViews(
        c2w=truth.test_c2w.astype(np.float32),
        hdr=truth.test_hdr.astype(np.float32),
        ldr=truth.test_ldr.astype(np.float32) / 255.0,
        exposures_s=np.asarray(truth.test_exposures_s, np.float32),
    )
