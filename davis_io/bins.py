"""Exposure-synchronised event bins: equal-count splits, trapezoid weights and the h() calibration.

For one APS frame the DVS events inside its exposure window (``start <= t <= end``, both ends
included) are split into ``b`` bins holding equal numbers of events. Bins give the ``b + 1`` latent
time points of the exposure (pose and sharp frame at each), the trapezoid weights of the exposure
integral over those points, the signed event count per bin and pixel, and the counts corrected by
the fractional offsets h() of See-NeRF's photometric calibration (supplementary eqs. 16-17).

Choice of the outer time points. The reference pipeline takes the first and the last event of the
window as the outer latent time points. Here they are the APS exposure start and end instead:

* the blurry frame integrates radiance from exposure start to exposure end, so trapezoid weights
  over ``[exposure_start, s_1, ..., s_{b-1}, exposure_end]`` approximate exactly that integral,
  while weights over ``[first event, ..., last event]`` approximate a shorter one whenever the
  first event comes late or the last one early (dim scenes, slow motion, few events);
* they are defined for every frame, including frames with zero or one event (or all events in
  the same microsecond), where the reference divides by zero;
* the inner split times ``s_k`` and the h() offsets are unchanged: the calibration only uses
  bin boundaries between two bins, never the start of bin 0 or the end of the last bin, so the
  calibrated counts equal the reference's for every frame.

The gaps follow §1.6 as written (``gap_end = bin_end - t_last + 1``); the reference's real-data
script stores ``t_last - 1`` instead, which makes its gaps one microsecond longer.

Latent time point ``i`` is ``split_us[i]``; weight ``i`` is the trapezoid weight of that point, so
``sum(weights) == 1`` and the blurry frame is ``sum_i weights[i] * E(split_us[i])``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.errors import DavisIOError
from davis_io.types import EVENT_DTYPE

__all__ = [
    "BinningError",
    "ExposureBins",
    "bin_exposure",
    "split_times_us",
    "subdivide",
    "trapezoid_weights",
]

_RAW_DTYPE = np.int16
_RAW_LIMITS = np.iinfo(_RAW_DTYPE)


class BinningError(DavisIOError):
    """Events or an exposure window cannot be binned as given."""


@dataclass(frozen=True)
class ExposureBins:
    """The event bins of one exposure.

    Attributes:
        split_us: ``(b + 1,)`` int64 latent time points in µs: exposure start, the start time of
            bins 1 .. b-1 (time of their first event), exposure end. Non-decreasing.
        weights: ``(b + 1,)`` float64 trapezoid weights of the exposure integral, sum 1.
        raw: ``(b, H, W)`` int16 signed event count per bin and pixel (saturates at the int16
            limits; ``calibrated`` keeps the exact value).
        calibrated: ``(b, H, W)`` float32 counts with the h() offsets added.
        event_count: number of events inside the exposure window.
    """

    split_us: np.ndarray
    weights: np.ndarray
    raw: np.ndarray
    calibrated: np.ndarray
    event_count: int


def split_times_us(window_t_us: np.ndarray, start_us: int, end_us: int, b: int) -> np.ndarray:
    """Latent time points of an exposure from the sorted event times inside it.

    Event ``n`` of ``N`` (0-based, time order) belongs to bin ``floor(n * b / N)``, so bin ``k``
    starts at event ``ceil(k * N / b)`` and ``s_k`` is that event's time. A bin index past the last
    event (only when ``N < b``) gives ``s_k = end_us``. With no event at all, the points are
    evenly spaced in time, since nothing tells where the motion happened.

    Args:
        window_t_us: ``(N,)`` int64 times in µs of the events in the window, sorted.
        start_us: exposure start, µs.
        end_us: exposure end, µs (``>= start_us``).
        b: number of bins, ``>= 1``.

    Returns:
        ``(b + 1,)`` int64: ``[start_us, s_1, ..., s_{b-1}, end_us]``.
    """
    count = len(window_t_us)
    inner = np.arange(1, b, dtype=np.int64)
    if count == 0:
        inner_us = start_us + (inner * (end_us - start_us)) // b
    else:
        first_index = -((-inner * count) // b)  # ceil(k * N / b) in integers
        found = window_t_us[np.minimum(first_index, count - 1)]
        inner_us = np.where(first_index < count, found, end_us)
    return np.concatenate(([start_us], inner_us, [end_us])).astype(np.int64)


def subdivide(points: np.ndarray, parts: int) -> np.ndarray:
    """Non-decreasing ``points`` with ``parts - 1`` evenly spaced ones added between neighbours.

    Args:
        points: ``(P,)`` time points (any units).
        parts: pieces each interval is cut into (1 returns the points).

    Returns:
        ``((P - 1) * parts + 1,)`` float64 points; point ``k * parts`` is ``points[k]``.
    """
    points = np.asarray(points, np.float64)
    steps = np.arange(parts) / parts
    inner = points[:-1, None] + steps * np.diff(points)[:, None]
    return np.concatenate([inner.ravel(), points[-1:]])


def trapezoid_weights(split_us: np.ndarray) -> np.ndarray:
    """Trapezoid weights of the exposure integral over the latent time points.

    With ``T = [t_0, t_0, t_1, ..., t_b, t_b]`` (ends repeated), ``w_i = (T[i+2] - T[i]) /
    (2 (t_b - t_0))``, so ``w_0 = (t_1 - t_0) / 2T``, ``w_b = (t_b - t_{b-1}) / 2T`` and the
    weights sum to 1. A zero-length window (``t_b == t_0``) gives equal weights.

    Args:
        split_us: ``(b + 1,)`` non-decreasing time points in µs.

    Returns:
        ``(b + 1,)`` float64 weights summing to 1.
    """
    points = np.asarray(split_us, dtype=np.int64)
    span_us = int(points[-1] - points[0])
    if span_us == 0:
        return np.full(len(points), 1.0 / len(points))
    padded = np.concatenate(([points[0]], points, [points[-1]]))
    return (padded[2:] - padded[:-2]).astype(np.float64) / (2.0 * span_us)


def bin_exposure(
    events: np.ndarray,
    exposure_start_us: int,
    exposure_end_us: int,
    b: int,
    width: int,
    height: int,
    contrast: tuple[np.ndarray, np.ndarray] | None = None,
) -> ExposureBins:
    """Bin the events of one exposure and calibrate the counts (photometric calibration, h()).

    Args:
        events: event array (``EVENT_DTYPE``) sorted by ``t``; only events with
            ``exposure_start_us <= t <= exposure_end_us`` are used, so the whole recording or
            a pre-cut slice may be passed.
        exposure_start_us: exposure start (SOE), µs.
        exposure_end_us: exposure end (EOE), µs.
        b: number of bins, ``>= 1``.
        width: sensor width in pixels.
        height: sensor height in pixels.
        contrast: per-pixel ``(H * W,)`` ln-intensity change of one ON and of one OFF event
            (the sensor's calibrated thresholds); ``calibrated`` is then the ln change per bin
            instead of a count, each event and offset weighted by its polarity's threshold.

    Returns:
        The bins of this exposure (see :class:`ExposureBins`).

    Raises:
        BinningError: bad ``b``, a window that ends before it starts, unsorted events or events
            outside the sensor.
    """
    window, times = _cut_window(events, exposure_start_us, exposure_end_us, b)
    count = len(window)
    _check_pixels(window, width, height)
    split_us = split_times_us(times, exposure_start_us, exposure_end_us, b)
    key = _bin_pixel_keys(window, b, width, height)
    polarity = window["p"].astype(np.float64)
    pixels = width * height
    counts = np.bincount(key, weights=polarity, minlength=b * pixels)
    size = (np.ones(pixels), np.ones(pixels)) if contrast is None else contrast
    is_on = polarity > 0
    weighted = counts
    if contrast is not None:
        pixel = key % pixels
        change = np.where(is_on, size[0][pixel], -size[1][pixel])
        weighted = np.bincount(key, weights=change, minlength=b * pixels)
    offsets = _calibration_offsets(times, is_on, key, split_us, b, pixels, size)
    shape = (b, height, width)
    raw = np.clip(counts, _RAW_LIMITS.min, _RAW_LIMITS.max).astype(_RAW_DTYPE).reshape(shape)
    calibrated = (weighted + offsets.ravel()).astype(np.float32).reshape(shape)
    return ExposureBins(split_us, trapezoid_weights(split_us), raw, calibrated, count)


def _bin_pixel_keys(window: np.ndarray, b: int, width: int, height: int) -> np.ndarray:
    """``bin * (width * height) + y * width + x`` of each event, int32 (or int64 if needed).

    Event ``n`` of ``N`` is in bin ``floor(n b / N)``, i.e. bin ``k`` holds events
    ``ceil(k N / b)`` to ``ceil((k + 1) N / b) - 1``.
    """
    count = len(window)
    key_type = np.int32 if b * width * height < np.iinfo(np.int32).max else np.int64
    first_of_bin = -((-np.arange(b + 1, dtype=np.int64) * count) // b)
    bin_offset = np.arange(b, dtype=key_type) * key_type(width * height)
    key = np.repeat(bin_offset, np.diff(first_of_bin))
    key += window["y"].astype(key_type) * key_type(width)
    key += window["x"]
    return key


def _cut_window(
    events: np.ndarray, start_us: int, end_us: int, b: int
) -> tuple[np.ndarray, np.ndarray]:
    """The events with ``start_us <= t <= end_us`` and their times (contiguous), once checked."""
    if events.dtype != EVENT_DTYPE:
        raise BinningError(f"events have dtype {events.dtype}, expected {EVENT_DTYPE}")
    if int(b) != b or b < 1:
        raise BinningError(f"number of bins b={b!r} must be a whole number >= 1")
    if end_us < start_us:
        raise BinningError(
            f"exposure window ends ({end_us} µs) before it starts ({start_us} µs): "
            "check the frame timestamps"
        )
    times = np.ascontiguousarray(events["t"])
    if len(times) > 1 and np.any(times[1:] < times[:-1]):
        raise BinningError("events are not sorted by time: sort them (stable) before binning")
    first = np.searchsorted(times, start_us, side="left")
    stop = np.searchsorted(times, end_us, side="right")
    return events[first:stop], times[first:stop]


def _check_pixels(window: np.ndarray, width: int, height: int) -> None:
    """Raise when an event lies outside a ``width x height`` sensor."""
    if len(window) and (window["x"].max() >= width or window["y"].max() >= height):
        raise BinningError(
            f"events reach x={int(window['x'].max())}, y={int(window['y'].max())} on a "
            f"{width}x{height} sensor: the events and the sensor size stated for them disagree "
            "(a damaged file, or the size of another sensor); check the recording's stated size"
        )


def _calibration_offsets(
    times: np.ndarray,
    is_on: np.ndarray,
    key: np.ndarray,
    split_us: np.ndarray,
    b: int,
    pixels: int,
    size: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """Fractional h() offsets per bin and pixel, ``(b, pixels)`` float64.

    Events are in time order, so the first event of a (bin, pixel) key has the smallest index
    and time, the last the largest. ``2 * index + is_on`` keeps that order and carries the
    polarity along, so one minimum and one maximum per key give both. An offset is a share of
    the event at the boundary, so it is that share of its polarity's ``size`` at the pixel.
    """
    count = len(times)
    code_type = np.int64 if 2 * count + 1 > np.iinfo(key.dtype).max else key.dtype
    code = np.arange(count, dtype=code_type) * 2 + is_on
    first_code = np.full(b * pixels, 2 * count + 2, dtype=code_type)
    last_code = np.full(b * pixels, -1, dtype=code_type)
    first_t = np.full(b * pixels, np.iinfo(np.int64).max, dtype=np.int64)
    last_t = np.full(b * pixels, np.iinfo(np.int64).min, dtype=np.int64)
    np.minimum.at(first_code, key, code)
    np.maximum.at(last_code, key, code)
    np.minimum.at(first_t, key, times)
    np.maximum.at(last_t, key, times)
    has_event = (last_code >= 0).reshape(b, pixels)
    # Polarity +1 / -1 where the key has events, 0 where it has none.
    first_p = np.where(has_event, 2.0 * (first_code.reshape(b, pixels) & 1) - 1, 0.0)
    last_p = np.where(has_event, 2.0 * (last_code.reshape(b, pixels) & 1) - 1, 0.0)
    first_t = np.where(has_event, first_t.reshape(b, pixels), 0)
    last_t = np.where(has_event, last_t.reshape(b, pixels), 0)
    # The signed size of each (bin, pixel)'s last event: +size_on, -size_off or 0.
    last_size = np.where(last_p > 0, size[0], np.where(last_p < 0, -size[1], 0.0))
    offsets = np.zeros((b, pixels), dtype=np.float64)
    for i in range(b - 1):
        edges = _BinEdges(
            has_event[i],
            has_event[i + 1],
            last_t[i],
            first_t[i + 1],
            last_p[i],
            first_p[i + 1],
            last_size[i],
        )
        _boundary_offsets(offsets, i, edges, int(split_us[i + 1]))
    # Last bin: half its last event wherever it has events (expected residual of a uniform
    # crossing).
    offsets[b - 1] += 0.5 * last_size[b - 1]
    return offsets


@dataclass(frozen=True)
class _BinEdges:
    """Per pixel, what touches the boundary between bin i and bin i+1.

    Where a bin has no event at a pixel its time and polarity are 0; the masks ``here`` and
    ``after`` keep those out of every result. ``last_size`` is the signed size of bin i's last
    event (its polarity, or its polarity's threshold at the pixel).
    """

    here: np.ndarray
    after: np.ndarray
    last_t: np.ndarray
    next_t: np.ndarray
    last_p: np.ndarray
    next_p: np.ndarray
    last_size: np.ndarray


def _boundary_offsets(offsets: np.ndarray, i: int, edges: _BinEdges, boundary_us: int) -> None:
    """Add the offsets of the boundary between bin ``i`` and bin ``i + 1`` (in place).

    Same polarity p on both sides: the threshold crossing is placed linearly in time between the
    last event of bin i and the first of bin i+1; the part before the boundary,
    ``h = gap_end / (gap_end + gap_pre)`` with ``gap_end = boundary - t_last + 1`` and
    ``gap_pre = t_first - boundary + 1`` (the +1 keeps both gaps positive), moves from bin i+1 to
    bin i (+p h, -p h: the pixel's total is kept). Opposite polarities: nothing. Bin i+1 empty at
    the pixel: bin i gets +p_last / 2. Bin i empty: nothing.
    """
    same = edges.here & edges.after & (edges.last_p == edges.next_p)
    gap_end = (boundary_us + 1 - edges.last_t).astype(np.float64)
    gap_pre = (edges.next_t + 1 - boundary_us).astype(np.float64)
    share = np.where(same, edges.last_size * gap_end / np.maximum(gap_end + gap_pre, 1.0), 0.0)
    offsets[i] += share
    offsets[i + 1] -= share
    offsets[i] += np.where(edges.here & ~edges.after, 0.5 * edges.last_size, 0.0)
