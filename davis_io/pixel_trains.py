"""``PixelTrains``: events regrouped as each pixel's own train, searchable by pixel and time.

A camera sends events in time order, all pixels interleaved; what a pixel did around a moment
(its intervals, the events on either side of a time point) needs its own events together. The
trains are sorted by pixel, each in time order, and one integer key per event (pixel, then time
in ticks) lets a single ``searchsorted`` find every pixel's neighbours of a time at once.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["Neighbours", "PixelTrains", "pixel_order", "pixel_trains"]

_TIME_BITS = 36
"""Bits of a time in its key: 19 hours of microsecond ticks (9.5 of half microseconds)."""


@dataclass(frozen=True)
class Neighbours:
    """Every pixel's events on either side of a time point, as indices into the trains.

    Attributes:
        before: ``(P,)`` index of the pixel's last event at or before the point (valid where
            ``has_before``).
        after: ``(P,)`` index of its first event after the point; where the pixel has none,
            the next pixel's first event (or the trains' length).
        has_before: ``(P,)`` bool the pixel has an event at or before the point.
        has_after: ``(P,)`` bool it has one after.
    """

    before: np.ndarray
    after: np.ndarray
    has_before: np.ndarray
    has_after: np.ndarray


@dataclass(frozen=True)
class PixelTrains:
    """Events sorted by pixel, then time.

    Attributes:
        pixel: ``(N,)`` int64 the event's pixel, ``0 .. pixel_count - 1``, ascending.
        time_us: ``(N,)`` its time, in time order within a pixel.
        order: ``(N,)`` where each event was in the input (``input[order]`` is sorted).
        pixel_count: P.
        tick_us: the keys' time resolution (times are whole ticks apart, or rounded to them).
    """

    pixel: np.ndarray
    time_us: np.ndarray
    order: np.ndarray
    pixel_count: int
    tick_us: float

    @cached_property
    def _origin_us(self) -> float:
        # One tick before every event: a point before a pixel's first event has nothing before.
        return float(np.min(self.time_us)) - self.tick_us if len(self.time_us) else 0.0

    def _key(self, pixel: np.ndarray, time_us: np.ndarray | float) -> np.ndarray:
        ticks = np.rint((np.asarray(time_us, np.float64) - self._origin_us) / self.tick_us)
        return (pixel << _TIME_BITS) | np.clip(ticks, 0, 2**_TIME_BITS - 1).astype(np.int64)

    @cached_property
    def _keys(self) -> np.ndarray:
        return self._key(self.pixel, self.time_us)

    @cached_property
    def pixels(self) -> np.ndarray:
        """``(P,)`` int64 every pixel, ``0 .. P-1``."""
        return np.arange(self.pixel_count, dtype=np.int64)

    def intervals(self) -> np.ndarray:
        """The intervals between consecutive events of one pixel, every pixel's in a row."""
        return np.diff(self.time_us)[self.pixel[1:] == self.pixel[:-1]]

    def around(self, time_us: float) -> Neighbours:
        """Every pixel's last event at or before ``time_us`` and its first after."""
        after = np.searchsorted(self._keys, self._key(self.pixels, time_us), side="right")
        if len(self.pixel) == 0:
            none = np.zeros(self.pixel_count, bool)
            return Neighbours(after, after, none, none)
        before, later = np.maximum(after - 1, 0), np.minimum(after, len(self.pixel) - 1)
        return Neighbours(
            before,
            after,
            (after > 0) & (self.pixel[before] == self.pixels),
            (after < len(self.pixel)) & (self.pixel[later] == self.pixels),
        )


def pixel_trains(
    pixel: np.ndarray, time_us: np.ndarray, pixel_count: int | None = None, tick_us: float = 1.0
) -> PixelTrains:
    """Group events by pixel.

    Args:
        pixel: ``(N,)`` each event's pixel, ``0 .. pixel_count - 1``.
        time_us: ``(N,)`` its time; events of one pixel in time order.
        pixel_count: P; None: one more than the largest pixel.
        tick_us: resolution of the times (0.5 where they fall on half microseconds).
    """
    pixel = np.asarray(pixel, np.int64)
    if pixel_count is None:
        pixel_count = int(pixel.max()) + 1 if len(pixel) else 0
    order = pixel_order(pixel, pixel_count)
    return PixelTrains(pixel[order], np.asarray(time_us)[order], order, pixel_count, tick_us)


def pixel_order(pixel: np.ndarray, pixel_count: int) -> np.ndarray:
    """The stable order that groups events by pixel, each pixel's events kept in their order.

    A radix sort where the pixels fit 16 bits (numpy's stable sort of 16-bit keys), which is
    several times faster than a merge sort of wider keys.

    Args:
        pixel: ``(N,)`` each event's pixel (or any group number), ``0 .. pixel_count - 1``.
        pixel_count: P.
    """
    keys = np.asarray(pixel, np.uint16 if pixel_count <= 1 << 16 else np.int64)
    return np.argsort(keys, kind="stable")
