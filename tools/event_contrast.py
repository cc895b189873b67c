"""How much of the true log-intensity change an emulated session's events carry, and how late.

    python tools/event_contrast.py SESSION [--bins 4] [--frames 3] [--threshold THETA]
        [--latency-ms MS | --scan-latency] [--calibration measured|truth]
        [--true thresholds,factors,latency] [--spans]

For an emulated session, renders (noise-free) what each pixel sees at the latent time points of
a few exposures and compares the true change of ln intensity over each bin with the change the
bin's events imply (calibrated counts times the contrast threshold: by default the mean of the
median pixel's true ON and OFF thresholds, from the session's truth). Over the pixels whose
true change exceeds the threshold it prints the median ratio of the two, the least-squares slope
of the event change on the true one (also for rises and falls apart), and their correlation. A
ratio under 1 means the events undercount contrast.

``--calibration`` reads the bins as a fit does instead (``contrast_bins``: events in
light time, each weighing its pixel's threshold), with the session's measured calibration or the
sensor's true values: what the fit's event loss is given. A slope under 1 with both is the
pixel; under 1 with the measured values alone is the calibration (its latency, mostly).
``--true`` takes the named parts of the measured calibration from the truth instead (the median
pixel's thresholds, every pixel's factors, the latency), to tell which part costs the contrast.
``--spans`` compares the changes as the fit's event loss does (``seenerf.train.losses``): over the
spans between the latent points where a pixel had fired all it owed (``davis_io.settled``), so
the slope is the contrast scale that loss prefers.

Events come late: a pixel's photoreceptor low-pass lags in the dark, and its refractory period
lets a strong edge out at only one event per dead time, so the counts of a bin describe a change
that happened earlier. ``--latency-ms`` compares each bin with the true change that much
earlier; ``--scan-latency`` tries 0 to 16 ms and names the latency the events agree with best.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from davis_io.emulator import EmulatedCamera
from davis_io.emulator.dvs import lin_log
from davis_io.session import DEFAULT_BINS, SensorCalibration, Session, contrast_bins

SCANNED_LATENCIES_MS = tuple(range(0, 17, 2))

TRUE_PARTS = ("thresholds", "factors", "latency")
"""Parts of a calibration ``--true`` can take from the truth."""


def log_changes(
    session_dir: Path,
    b: int,
    frames: int,
    threshold: float | None,
    latencies_us: tuple[int, ...] = (0,),
    calibration: SensorCalibration | None = None,
    spans: bool = False,
):
    """True and event-implied ln-intensity changes per bin of ``frames`` exposures, flattened.

    The session is read and the emulator built once, whatever the number of latencies.

    Args:
        latencies_us: for each, the true change is taken over each bin's time span moved this
            much earlier.
        calibration: read the bins as a fit does (in light time, in ln units) with these
            sensor values, instead of the stored counts times ``threshold``.
        spans: compare the changes over the spans between settled points (:func:`settled_spans`)
            rather than bin by bin; needs ``calibration``.

    Returns:
        The true changes ``(len(latencies_us), N)``, the implied ones ``(N,)``, and the
        threshold (the true one unless given: the floor of :func:`agreement`).
    """
    if spans and calibration is None:
        raise ValueError("spans compare the bins as a fit reads them: give a calibration")
    with Session.open(session_dir) as session:
        bins = (
            session.bins(b)
            if calibration is None
            else contrast_bins(session, b, calibration, settled=spans)
        )
        sensor = session.truth().sensor
    camera = EmulatedCamera.of_session(session_dir)
    threshold = threshold or 0.5 * (sensor["median_threshold_on"] + sensor["median_threshold_off"])
    linear_below = camera.sensor.dvs.linlog_threshold
    chosen = np.linspace(0, len(bins.split_us) - 1, frames).round().astype(int)
    unit = threshold if calibration is None else 1.0
    true, implied = [], []
    for latency_us in latencies_us:
        changes, implied = [], []
        for frame in chosen:
            seen = np.stack(
                [
                    lin_log(255.0 * camera.sensor_image(c2w), linear_below).ravel()
                    for c2w in camera.trajectory.c2w(bins.split_us[frame] - latency_us)
                ]
            )
            counted = unit * bins.calibrated[frame].reshape(b, -1)
            if spans:
                true_span, counted_span = settled_spans(
                    seen, counted, bins.settled[frame].reshape(b + 1, -1)
                )
                changes.append(true_span)
                implied.append(counted_span)
            else:
                changes.append(np.diff(seen, axis=0).ravel())
                implied.append(counted.ravel())
        true.append(np.concatenate(changes))
    return np.stack(true), np.concatenate(implied), threshold


def settled_spans(
    seen: np.ndarray, counted: np.ndarray, settled: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The true and counted changes over each span between consecutive settled points.

    Args:
        seen: ``(b+1, P)`` true ln intensity at the latent points.
        counted: ``(b, P)`` the bins' ln changes.
        settled: ``(b+1, P)`` bool, where each pixel had fired all it owed.

    Returns:
        Two ``(S,)`` arrays, one entry per span (point by point, then pixel by pixel).
    """
    total = np.concatenate([np.zeros((1, counted.shape[1])), np.cumsum(counted, 0)])
    last_seen, last_total, started = seen[0], total[0], settled[0]
    true_spans, counted_spans = [], []
    for point in range(1, len(seen)):
        ends = started & settled[point]
        true_spans.append((seen[point] - last_seen)[ends])
        counted_spans.append((total[point] - last_total)[ends])
        last_seen = np.where(settled[point], seen[point], last_seen)
        last_total = np.where(settled[point], total[point], last_total)
        started = started | settled[point]
    return np.concatenate(true_spans), np.concatenate(counted_spans)


def _slope(true: np.ndarray, implied: np.ndarray) -> float:
    return float((true @ implied) / (true @ true)) if len(true) else float("nan")


def agreement(true: np.ndarray, implied: np.ndarray, threshold: float) -> dict:
    """Median ratio, slopes (all, rises, falls) and correlation where ``|true| > threshold``."""
    moved = np.abs(true) > threshold
    true, implied = true[moved], implied[moved]
    return {
        "pixels": int(moved.sum()),
        "ratio": float(np.median(implied / true)),
        "slope": _slope(true, implied),
        "slope_rise": _slope(true[true > 0], implied[true > 0]),
        "slope_fall": _slope(true[true < 0], implied[true < 0]),
        "correlation": float(np.corrcoef(true, implied)[0, 1]),
    }


def sensor_values(
    session_dir: Path, source: str, true_parts: tuple[str, ...] = ()
) -> SensorCalibration:
    """The session's measured calibration (``measured``) or its sensor's true values.

    ``true_parts`` (of :data:`TRUE_PARTS`) are taken from the truth in a measured calibration.
    """
    with Session.open(session_dir) as session:
        if source == "truth":
            return session.truth().sensor_calibration()
        calibration = session.calibration()
        truth = session.truth().sensor_calibration() if true_parts else None
    if calibration is None:
        raise SystemExit(f"{session_dir}: not calibrated yet; run seecap calibrate first")
    return with_true_parts(calibration, truth, true_parts) if truth else calibration


def with_true_parts(
    measured: SensorCalibration, truth: SensorCalibration, parts: tuple[str, ...]
) -> SensorCalibration:
    """``measured`` with the named parts (:data:`TRUE_PARTS`) replaced by the truth's."""
    unknown = set(parts) - set(TRUE_PARTS)
    if unknown:
        raise ValueError(f"unknown calibration parts {sorted(unknown)}; choose from {TRUE_PARTS}")
    fields = {
        "thresholds": ("threshold_on", "threshold_off"),
        "factors": ("pixel_factor_on", "pixel_factor_off"),
        "latency": ("latency_us",),
    }
    taken = {name: getattr(truth, name) for part in parts for name in fields[part]}
    return dataclasses.replace(measured, **taken)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("session", type=Path, help="an emulated session folder")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS)
    parser.add_argument("--frames", type=int, default=3, help="exposures to compare")
    parser.add_argument("--threshold", type=float, default=None, help="default: the true one")
    latency = parser.add_mutually_exclusive_group()
    latency.add_argument("--latency-ms", type=float, default=0.0, help="event latency assumed")
    latency.add_argument("--scan-latency", action="store_true", help="try 0 to 16 ms")
    parser.add_argument(
        "--calibration",
        choices=("measured", "truth"),
        help="read the bins as a fit does, with the measured or the true sensor values",
    )
    parser.add_argument(
        "--true",
        default="",
        help=f"with --calibration measured: parts taken from the truth, of {','.join(TRUE_PARTS)}",
    )
    parser.add_argument(
        "--spans",
        action="store_true",
        help="with --calibration: compare over the spans between settled points, as the fit does",
    )
    args = parser.parse_args()
    true_parts = tuple(part for part in args.true.split(",") if part)
    if (true_parts and args.calibration != "measured") or (args.spans and not args.calibration):
        parser.error("--true needs --calibration measured; --spans needs --calibration")
    latencies = SCANNED_LATENCIES_MS if args.scan_latency else (args.latency_ms,)
    true, implied, threshold = log_changes(
        args.session,
        args.bins,
        args.frames,
        args.threshold,
        tuple(round(latency_ms * 1000) for latency_ms in latencies),
        sensor_values(args.session, args.calibration, true_parts) if args.calibration else None,
        args.spans,
    )
    unit = "span" if args.spans else "bin"
    results = []
    for latency_ms, true_changes in zip(latencies, true, strict=True):
        found = agreement(true_changes, implied, threshold)
        results.append((found["correlation"], latency_ms))
        print(
            f"latency {latency_ms:g} ms: {found['pixels']} pixels whose ln intensity changed by "
            f"more than {threshold:g} in a {unit}; event / true change: median ratio "
            f"{found['ratio']:.3f}, slope {found['slope']:.3f} (rises {found['slope_rise']:.3f}, "
            f"falls {found['slope_fall']:.3f}), correlation {found['correlation']:.3f}"
        )
    if args.scan_latency:
        print(f"the events agree best with the true changes {max(results)[1]:g} ms earlier")


if __name__ == "__main__":
    main()
