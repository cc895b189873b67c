"""How much of the true log-intensity change of an exposure an emulated session's events carry.

    python tools/event_contrast.py SESSION [--bins 4] [--frames 3] [--threshold THETA]

For an emulated session, renders (noise-free) what each pixel sees at the start and at the end
of a few exposures and compares the true change of ln intensity with the change the binned
events imply (calibrated counts summed over the bins, times the contrast threshold: by default
the one the camera configuration states). Over the
pixels whose true change exceeds the threshold it prints the median ratio of the two, the
least-squares slope of the event change on the true one, and their correlation. A ratio under
1 means the events undercount contrast, and a fit at that threshold learns a field whose log
contrast is compressed by about as much (``log_contrast`` in a fit's ``metrics.json``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from davis_io.emulator import DVS_PRESETS, EmulatedCamera
from davis_io.emulator.dvs import lin_log
from davis_io.poses.estimate import stated_threshold
from davis_io.session import Session


def log_changes(session_dir: Path, b: int, frames: int, threshold: float | None):
    """True and event-implied ln-intensity changes over ``frames`` exposures, pixels flattened.

    Returns:
        The true changes, the implied ones, and the threshold used.
    """
    with Session.open(session_dir) as session:
        bins = session.bins(b)
        settings = dict(session.manifest.device_config["emulator"])
        threshold = threshold or stated_threshold(session)
    for stated in ("dvs_threshold_on", "dvs_threshold_off"):
        settings.pop(stated, None)
    camera = EmulatedCamera(**settings)
    linear_below = DVS_PRESETS[camera.config.dvs_preset].linlog_threshold
    true, implied = [], []
    for frame in np.linspace(0, len(bins.split_us) - 1, frames).round().astype(int):
        start_us, end_us = bins.split_us[frame, 0], bins.split_us[frame, -1]
        start, end = (
            lin_log(255.0 * camera.sensor_image(c2w), linear_below)
            for c2w in camera.trajectory.c2w(np.array([start_us, end_us]))
        )
        true.append((end - start).ravel())
        implied.append(threshold * bins.calibrated[frame].sum(axis=0).ravel())
    return np.concatenate(true), np.concatenate(implied), threshold


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("session", type=Path, help="an emulated session folder")
    parser.add_argument("--bins", type=int, default=4)
    parser.add_argument("--frames", type=int, default=3, help="exposures to compare")
    parser.add_argument("--threshold", type=float, default=None, help="default: the nominal one")
    args = parser.parse_args()
    true, implied, threshold = log_changes(args.session, args.bins, args.frames, args.threshold)
    moved = np.abs(true) > threshold
    true, implied = true[moved], implied[moved]
    print(f"{moved.sum()} pixels whose ln intensity changed by more than {threshold:g}")
    print(f"median ratio of event to true change: {np.median(implied / true):.3f}")
    print(f"slope of event on true change: {(true @ implied) / (true @ true):.3f}")
    print(f"correlation: {np.corrcoef(true, implied)[0, 1]:.3f}")


if __name__ == "__main__":
    main()
