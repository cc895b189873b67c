"""Reads a recorded session (and its truth, when emulated) into :class:`TrainingData`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from davis_io.geometry import interpolate_poses
from davis_io.session import Session, Truth
from seenerf.data.arrays import TestViews, TrainingData, TrainTruth, pixel_layout
from seenerf.errors import TrainingDataError

__all__ = ["load_training_data"]


def load_training_data(session_dir: Path | str, b: int, *, keep_lost: bool = False) -> TrainingData:
    """Frames, bins and poses of a session as float32 training arrays.

    Args:
        session_dir: the session folder.
        b: event bins per exposure (bins are computed from the events if not stored).
        keep_lost: also train on frames whose exposure window lost events.

    Raises:
        TrainingDataError: no poses for ``b`` yet, or no usable frame.
    """
    with Session.open(session_dir) as session:
        poses = session.poses(b)
        if poses is None:
            raise TrainingDataError(
                f"{session_dir}: no poses for b={b}; run `seecap poses {session_dir} --bins {b}` "
                "(seecap fit runs it when missing)"
            )
        table = session.frames_table()
        bins = session.bins(b)
        usable = np.flatnonzero(keep_lost | ~np.asarray(table.events_lost, bool))
        if len(usable) == 0:
            raise TrainingDataError(f"{session_dir}: every frame lost events; use keep_lost=True")
        frames = [session.frame(int(i)) for i in usable]
        scale = float(2 ** frames[0].bit_depth - 1)
        ldr = np.stack([f.image for f in frames]).astype(np.float32) / scale
        mix, channel = pixel_layout(session.color_filter, session.height, session.width)
        data = TrainingData(
            ldr=np.clip(ldr, 0.0, 1.0),
            exposure_s=(table.exposure_us[usable] * 1e-6).astype(np.float32),
            weights=bins.weights[usable].astype(np.float32),
            bins=bins.calibrated[usable].astype(np.float32),
            bins_raw=bins.raw[usable].astype(np.float32),
            c2w=poses.c2w[usable].astype(np.float32),
            intrinsics=poses.intrinsics.astype(np.float32),
            bounds=poses.bounds.astype(np.float32),
            mix=mix,
            channel=channel,
            monochrome=not session.color_filter.is_color,
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
