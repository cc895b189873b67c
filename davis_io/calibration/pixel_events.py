"""What each pixel's events say about its light, in the form frame/event consistency reads.

A pixel's events are read as a path of its ln intensity through the levels they mark
(:func:`event_path`). Counted in thresholds, an ON event ends a climb of one ON level and an
OFF event a fall of one OFF level. Between two events of the same polarity the light goes
straight from one level to the next. Between opposite events it went on past the first level
and came back, so the path rises (or falls) half a level past the first by the middle of the
interval, then goes straight to the second. Before a pixel's first event and after its last the
path is flat.

Why this reading: on ideal pixels (each event stamped at its crossing; thresholds 0.16 to
0.45) the light read flat at the last level (a staircase) lags the truth by 2.5 ms, which the
latency profile then takes for the sensor's; read straight through the levels alone it leads by
0.5 ms. This path has no lag and about half the RMS error of either (0.07 against 0.15-0.17).

For pixel ``p`` and frame ``k`` with exposure ``[s_k, e_k]``, let ``A(t)`` and ``B(t)`` be the
ON and OFF levels the path has climbed since ``s_k``; ``n(t) = theta_on A(t) - theta_off B(t)``
is then the change of ln intensity since ``s_k``. The frame integrates linear intensity over the
exposure, so

    ln g(v_k) = E(s_k) + ln M_k,   M_k = mean over the exposure of exp(n(t)),

with ``g`` the inverse response and ``E`` the pixel's ln intensity. ``M_k`` is a sum over the
path's straight pieces inside the exposure: a piece of share ``w`` that starts at ``n0`` and
climbs ``d`` adds ``w e^n0 (e^d - 1) / d``. :func:`pixel_events` cuts the pieces;
:func:`log_blur` evaluates ``ln M`` for any thresholds (per pixel) with its derivatives. From
one exposure start to the next only the levels climbed matter (:attr:`PixelEvents.between_on`
and ``between_off``, fractional where a start falls inside a piece).

Events come ``latency_us`` after the light change they report: the path is read that much later.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from davis_io.pixel_trains import PixelTrains, pixel_order

__all__ = ["EventPath", "LogBlur", "PixelEvents", "event_path", "log_blur", "pixel_events"]

_BLOCK = 1 << 20
"""Pieces summed at a time by :func:`log_blur`."""

_SERIES_CLIMB = 0.1
"""Climbs nearer 0 than this take the series of the blur's slope (:func:`_mean_exp`): in single
precision its closed form loses about 1e-7 / x of itself to cancellation."""

_SINGLE_EXPONENT = 80.0
"""The largest exponent :func:`log_blur` takes in single precision (which overflows at 88.7)."""


@dataclass(frozen=True)
class EventPath:
    """The knots of every pixel's path, sorted by pixel, then time.

    Attributes:
        pixel: ``(K,)`` int64 the knot's pixel, ``0 .. P-1``.
        time_us: ``(K,)`` float64 its time (mid-interval knots fall on half microseconds).
        on: ``(K,)`` float64 ON levels climbed there, from an origin of the pixel's own (only
            differences within a pixel mean anything).
        off: the same for OFF levels.
        pixel_count: P.
    """

    pixel: np.ndarray
    time_us: np.ndarray
    on: np.ndarray
    off: np.ndarray
    pixel_count: int

    @cached_property
    def _trains(self) -> PixelTrains:
        # Already in train order: the knots' indices are the trains'.
        order = np.arange(len(self.pixel))
        return PixelTrains(self.pixel, self.time_us, order, self.pixel_count, tick_us=0.5)

    @property
    def pixels(self) -> np.ndarray:
        """``(P,)`` int64 every pixel, ``0 .. P-1``."""
        return self._trains.pixels

    def read(self, time_us: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every pixel's ON and OFF levels at ``time_us`` ``(P,)``, and its first knot after it.

        A pixel without knots after ``time_us`` gets the next pixel's first knot.
        """
        near = self._trains.around(time_us)
        if len(self.pixel) == 0:
            return np.zeros(self.pixel_count), np.zeros(self.pixel_count), near.after
        before, later = near.before, np.minimum(near.after, len(self.pixel) - 1)
        both = near.has_before & near.has_after
        span = np.where(both, self.time_us[later] - self.time_us[before], 1.0)
        part = np.where(both, (time_us - self.time_us[before]) / span, 0.0)
        levels = []
        for level in (self.on, self.off):
            value = np.where(
                near.has_before, level[before], np.where(near.has_after, level[later], 0.0)
            )
            levels.append(np.where(both, value + part * (level[later] - level[before]), value))
        return levels[0], levels[1], near.after


def event_path(
    times_us: np.ndarray, pixel_index: np.ndarray, is_on: np.ndarray, pixel_count: int
) -> EventPath:
    """The path of the chosen pixels' light through their events (see the module).

    Args:
        times_us: ``(N,)`` event times, sorted.
        pixel_index: ``(N,)`` the event's pixel among the chosen ones, ``0 .. P-1`` (events of
            other pixels removed before).
        is_on: ``(N,)`` bool polarity.
        pixel_count: P.
    """
    order = pixel_order(pixel_index, pixel_count)  # then by time
    time = np.asarray(times_us, np.int64)[order].astype(np.float64)
    pixel = np.asarray(pixel_index, np.int64)[order]
    on = np.asarray(is_on, bool)[order]
    climbed_on = np.cumsum(on, dtype=np.float64)
    climbed_off = np.arange(1.0, len(on) + 1) - climbed_on
    starts = np.ones(len(pixel), bool)
    starts[1:] = pixel[1:] != pixel[:-1]
    turns = np.zeros(len(pixel), bool)  # the next event is the same pixel's, of the other sign
    turns[:-1] = ~starts[1:] & (on[1:] != on[:-1])
    # Each event's knot, after the level before a pixel's first event (a microsecond earlier,
    # so that step stays sharp) and before the half-level turn to an opposite neighbour.
    slots = 1 + starts + turns
    at = np.cumsum(slots) - slots + starts
    size = int(slots.sum())
    first, turn = np.flatnonzero(starts), np.flatnonzero(turns)  # few: gathered by index
    knots = [np.empty(size), np.empty(size), np.empty(size)]
    knot_pixel = np.empty(size, np.int64)
    lead, mid, following = at[first] - 1, at[turn] + 1, turn + 1
    for column, event, before, middle in zip(
        knots,
        (time, climbed_on, climbed_off),
        (time[first] - 1, climbed_on[first] - on[first], climbed_off[first] - ~on[first]),
        (
            0.5 * (time[turn] + time[following]),
            climbed_on[turn] + 0.5 * on[turn],
            climbed_off[turn] + 0.5 * ~on[turn],
        ),
        strict=True,
    ):
        column[at], column[lead], column[mid] = event, before, middle
    knot_pixel[at], knot_pixel[lead], knot_pixel[mid] = pixel, pixel[first], pixel[turn]
    return EventPath(knot_pixel, knots[0], knots[1], knots[2], pixel_count)


@dataclass(frozen=True)
class PixelEvents:
    """The path of ``P`` chosen pixels over ``F`` frames, cut into straight pieces.

    Attributes:
        between_on: ``(F-1, P)`` ON levels climbed from exposure start ``k`` to start ``k+1``.
        between_off: the same for OFF levels.
        flat_share: ``(F, P)`` share of each exposure over which the path stays at its level at
            the exposure's start (all of it for a pixel without events nearby).
        piece_key: ``(S,)`` int64 ``k * P + p`` of every other piece, sorted.
        piece_pixel: ``(S,)`` int32 its pixel ``p``.
        piece_share: ``(S,)`` float32 its duration over the exposure's.
        piece_on: ``(S,)`` float32 ON levels climbed from the exposure's start to the piece's.
        piece_off: the same for OFF levels.
        rise_on: ``(S,)`` float32 ON levels climbed over the piece.
        rise_off: the same for OFF levels.
    """

    between_on: np.ndarray
    between_off: np.ndarray
    flat_share: np.ndarray
    piece_key: np.ndarray
    piece_pixel: np.ndarray
    piece_share: np.ndarray
    piece_on: np.ndarray
    piece_off: np.ndarray
    rise_on: np.ndarray
    rise_off: np.ndarray

    @property
    def frames(self) -> int:
        """Number of frames F."""
        return self.flat_share.shape[0]

    @property
    def pixels(self) -> int:
        """Number of pixels P."""
        return self.flat_share.shape[1]


def _exposure_pieces(path: EventPath, start, end, start_levels, end_levels):
    """Every pixel's pieces of the path between ``start`` and ``end`` (read times, µs).

    A knot right at ``end`` ends a piece; the zero-length pieces after it are dropped.

    Returns:
        pixel, share, ON and OFF levels at the piece's start since ``start``, and the ON and OFF
        levels each piece climbs (zero-length pieces dropped).
    """
    on_start, off_start, first_inside = start_levels
    on_end, off_end, first_after = end_levels
    inside = np.maximum(first_after - first_inside, 0)
    points = inside + 2  # the start, the knots inside, the end
    offset = np.cumsum(points) - points
    total = int(points.sum())
    time, on, off = np.empty(total), np.empty(total), np.empty(total)
    time[offset], on[offset], off[offset] = start, on_start, off_start
    last = offset + points - 1
    time[last], on[last], off[last] = end, on_end, off_end
    count = int(inside.sum())
    if count:
        rank = np.arange(count) - np.repeat(np.cumsum(inside) - inside, inside)
        source = np.repeat(first_inside, inside) + rank
        target = np.repeat(offset + 1, inside) + rank
        time[target], on[target], off[target] = (
            path.time_us[source],
            path.on[source],
            path.off[source],
        )
    owner = np.repeat(path.pixels, points)
    piece = np.flatnonzero((owner[:-1] == owner[1:]) & (time[1:] > time[:-1]))
    pixel = owner[piece]
    return (
        pixel,
        (time[piece + 1] - time[piece]) / (end - start),
        on[piece] - on_start[pixel],
        off[piece] - off_start[pixel],
        on[piece + 1] - on[piece],
        off[piece + 1] - off[piece],
    )


def pixel_events(
    path: EventPath,
    exposure_start_us: np.ndarray,
    exposure_end_us: np.ndarray,
    latency_us: int = 0,
) -> PixelEvents:
    """Cut the path into the pieces of every exposure (at least one), read ``latency_us`` late."""
    frames, count = len(exposure_start_us), path.pixel_count
    starts = [path.read(float(s) + latency_us) for s in exposure_start_us]
    between_on = np.diff(np.stack([s[0] for s in starts]), axis=0).reshape(-1, count)
    between_off = np.diff(np.stack([s[1] for s in starts]), axis=0).reshape(-1, count)
    flat = np.zeros((frames, count))
    parts = []
    for k in range(frames):
        start = float(exposure_start_us[k]) + latency_us
        end = float(exposure_end_us[k]) + latency_us
        pixel, share, on, off, rise_on, rise_off = _exposure_pieces(
            path, start, end, starts[k], path.read(end)
        )
        level = (on == 0) & (off == 0) & (rise_on == 0) & (rise_off == 0)
        flat[k] = np.bincount(pixel[level], weights=share[level], minlength=count)
        ramp = ~level
        parts.append(
            (k * count + pixel[ramp], pixel[ramp].astype(np.int32))
            + tuple(c[ramp].astype(np.float32) for c in (share, on, off, rise_on, rise_off))
        )
    return PixelEvents(
        between_on,
        between_off,
        flat,
        *(np.concatenate(column) for column in zip(*parts, strict=True)),
    )


@dataclass(frozen=True)
class LogBlur:
    """``ln M`` ``(F, P)`` of every frame and pixel, and its derivatives.

    ``d_on`` and ``d_off`` (the same shape) are the derivatives by the pixel's ON and OFF
    thresholds.
    """

    value: np.ndarray
    d_on: np.ndarray | None = None
    d_off: np.ndarray | None = None


def _mean_exp(climb: np.ndarray, derivative: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """``(e^x - 1) / x``, the mean of ``e^(x t)`` over ``t`` in [0, 1], and its derivative.

    Within 1e-6 of 0 (flat pieces) they are 1 and 1/2 to within 1e-6. The derivative's terms
    cancel near 0, so within :data:`_SERIES_CLIMB` of it the derivative is its series
    ``1/2 + x/3 + x^2/8 + x^3/30 + x^4/144`` (within 2e-8 there). Both hold to about 1e-6 in
    single precision. ``climb`` is overwritten.
    """
    flat = np.abs(climb) < 1e-6
    climb[flat] = 1.0
    grown = np.expm1(climb)
    mean = grown / climb
    mean[flat] = 1.0
    if not derivative:
        return mean, None
    near = np.abs(climb) < _SERIES_CLIMB
    near &= ~flat
    x = climb[near]
    grown *= climb - 1
    grown += climb
    grown /= climb**2
    grown[near] = 0.5 + x * (1 / 3 + x * (1 / 8 + x * (1 / 30 + x / 144)))
    grown[flat] = 0.5
    return mean, grown


def log_blur(
    events: PixelEvents,
    theta_on: np.ndarray,
    theta_off: np.ndarray,
    derivatives: bool = False,
) -> LogBlur:
    """``ln M`` of every frame and pixel for per-pixel thresholds ``(P,)`` (or scalars).

    ``M = flat share + sum over pieces of share * e^n0 * (e^d - 1) / d``, at least the flat
    share and never zero (a piece's weight is positive). The derivatives cost twice the value
    again: only when asked. The pieces are summed in blocks of :data:`_BLOCK` (their keys are
    sorted): a whole sensor's tens of millions would otherwise cost fresh, page-faulted memory
    for every temporary. They are computed in single precision (the value within 1e-6 of
    double, in two thirds of the time) unless an exponent is too large for it; the slope near a
    flat piece, where its terms cancel, from its series (:func:`_mean_exp`).
    """
    frames, count = events.frames, events.pixels
    dtype = np.float32
    theta_on = np.broadcast_to(np.asarray(theta_on, dtype), (count,))
    theta_off = np.broadcast_to(np.asarray(theta_off, dtype), (count,))
    sums = [events.flat_share.ravel().copy()]
    if derivatives:
        sums += [np.zeros(frames * count), np.zeros(frames * count)]
    for start in range(0, len(events.piece_key), _BLOCK):
        block = slice(start, start + _BLOCK)
        key = events.piece_key[block]
        first, span = key[0], key[-1] - key[0] + 1
        pixel = events.piece_pixel[block]
        on, off = theta_on[pixel], theta_off[pixel]
        piece_on, piece_off = events.piece_on[block], events.piece_off[block]
        rise_on, rise_off = events.rise_on[block], events.rise_off[block]
        base = on * piece_on
        base -= off * piece_off
        if base.dtype == np.float32 and base.max() > _SINGLE_EXPONENT:
            base = base.astype(np.float64)  # a hot pixel's climb, beyond single precision
        np.exp(base, out=base)
        base *= events.piece_share[block]
        climb = on * rise_on
        climb -= off * rise_off
        mean, slope = _mean_exp(climb, derivatives)
        weights = [base * mean]
        if derivatives:
            weights += [
                base * (piece_on * mean + rise_on * slope),
                -base * (piece_off * mean + rise_off * slope),
            ]
        for total, weight in zip(sums, weights, strict=True):
            total[first : first + span] += np.bincount(key - first, weights=weight, minlength=span)
    total = sums[0].reshape(frames, count)
    if not derivatives:
        return LogBlur(np.log(total))
    return LogBlur(
        np.log(total),
        sums[1].reshape(frames, count) / total,
        sums[2].reshape(frames, count) / total,
    )
