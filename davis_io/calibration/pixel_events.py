"""What each pixel's events say about its light, in the form frame/event consistency reads.

For pixel ``p`` and frame ``k`` with exposure ``[s_k, e_k]``, let ``N(t)`` be the pixel's
signed event count since ``s_k``, its ON and OFF parts weighted by the thresholds:
``n(t) = theta_on N_on(t) - theta_off N_off(t)`` is then the change of ln intensity since
``s_k``. The frame integrates linear intensity over the exposure, so

    ln g(v_k) = E(s_k) + ln M_k,   M_k = mean over the exposure of exp(n(t)),

with ``g`` the inverse response and ``E`` the pixel's ln intensity. ``M_k`` is a sum over the
segments between the pixel's events, held here as flat arrays; :func:`log_blur` evaluates it for
any thresholds (per pixel) with its derivatives. Between exposure starts ``s_k`` and
``s_(k+1)`` only the counts matter (:attr:`PixelEvents.between_on` and ``between_off``).

Event times are moved ``latency_us`` earlier first, so they describe when the light changed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LogBlur", "PixelEvents", "log_blur", "pixel_events"]


@dataclass(frozen=True)
class PixelEvents:
    """The events of ``P`` chosen pixels over ``F`` frames.

    Attributes:
        between_on: ``(F-1, P)`` ON events from exposure start ``k`` to exposure start ``k+1``.
        between_off: the same for OFF events.
        segment_key: ``(S,)`` int64 ``k * P + p`` of each segment after an event inside an
            exposure.
        segment_pixel: ``(S,)`` int64 its pixel ``p``.
        segment_share: ``(S,)`` float64 its duration over the exposure's.
        segment_on: ``(S,)`` float64 ON events of the pixel since its exposure started, up to
            and including the one that opens the segment.
        segment_off: the same for OFF events.
        lead_share: ``(F, P)`` share of each exposure before the pixel's first event in it (all
            of it without events).
    """

    between_on: np.ndarray
    between_off: np.ndarray
    segment_key: np.ndarray
    segment_pixel: np.ndarray
    segment_share: np.ndarray
    segment_on: np.ndarray
    segment_off: np.ndarray
    lead_share: np.ndarray

    @property
    def frames(self) -> int:
        """Number of frames F."""
        return self.lead_share.shape[0]

    @property
    def pixels(self) -> int:
        """Number of pixels P."""
        return self.lead_share.shape[1]


def _exposure_segments(times, pixels, is_on, start_us, end_us, pixel_count):
    """Segments after each event of one exposure, pixel by pixel (see :class:`PixelEvents`)."""
    order = np.argsort(pixels, kind="stable")
    times, pixels, is_on = times[order], pixels[order], is_on[order]
    span = float(end_us - start_us)
    first = np.ones(len(pixels), bool)
    first[1:] = pixels[1:] != pixels[:-1]
    starts = np.flatnonzero(first)
    sizes = np.diff(np.append(starts, len(pixels)))
    on_total = np.cumsum(is_on)
    off_total = np.cumsum(~is_on)
    on = on_total - np.repeat(on_total[starts] - is_on[starts], sizes)
    off = off_total - np.repeat(off_total[starts] - ~is_on[starts], sizes)
    following = np.append(times[1:], end_us)
    following[np.append(starts[1:] - 1, len(times) - 1)] = end_us  # each pixel's last event
    lead = np.ones(pixel_count)
    lead[pixels[starts]] = (times[starts] - start_us) / span
    return pixels, (following - times) / span, on.astype(np.float64), off.astype(np.float64), lead


def pixel_events(
    times_us: np.ndarray,
    pixel_index: np.ndarray,
    is_on: np.ndarray,
    exposure_start_us: np.ndarray,
    exposure_end_us: np.ndarray,
    pixel_count: int,
    latency_us: int = 0,
) -> PixelEvents:
    """Collect the events of the chosen pixels.

    Args:
        times_us: ``(N,)`` event times, sorted.
        pixel_index: ``(N,)`` the event's pixel among the chosen ones, ``0 .. P-1`` (events of
            other pixels removed before).
        is_on: ``(N,)`` bool polarity.
        exposure_start_us: ``(F,)`` exposure starts.
        exposure_end_us: ``(F,)`` exposure ends.
        pixel_count: P.
        latency_us: events come this much after the light change they report.
    """
    times = np.asarray(times_us, np.int64) - int(latency_us)
    frames = len(exposure_start_us)
    between_on = np.zeros((max(frames - 1, 0), pixel_count))
    between_off = np.zeros_like(between_on)
    keys, chosen, shares, ons, offs = [], [], [], [], []
    lead = np.ones((frames, pixel_count))
    for k in range(frames):
        start, end = int(exposure_start_us[k]), int(exposure_end_us[k])
        if k + 1 < frames:
            first, stop = np.searchsorted(times, [start, int(exposure_start_us[k + 1])])
            polarity = is_on[first:stop]
            between_on[k] = np.bincount(pixel_index[first:stop][polarity], minlength=pixel_count)
            between_off[k] = np.bincount(pixel_index[first:stop][~polarity], minlength=pixel_count)
        first = np.searchsorted(times, start, side="left")
        stop = np.searchsorted(times, end, side="right")
        pixels, share, on, off, lead[k] = _exposure_segments(
            times[first:stop], pixel_index[first:stop], is_on[first:stop], start, end, pixel_count
        )
        chosen.append(pixels.astype(np.int64))
        keys.append(k * pixel_count + chosen[-1])
        shares.append(share)
        ons.append(on)
        offs.append(off)
    return PixelEvents(
        between_on,
        between_off,
        np.concatenate(keys) if keys else np.zeros(0, np.int64),
        np.concatenate(chosen) if chosen else np.zeros(0, np.int64),
        np.concatenate(shares) if shares else np.zeros(0),
        np.concatenate(ons) if ons else np.zeros(0),
        np.concatenate(offs) if offs else np.zeros(0),
        lead,
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


def log_blur(
    events: PixelEvents,
    theta_on: np.ndarray,
    theta_off: np.ndarray,
    derivatives: bool = False,
) -> LogBlur:
    """``ln M`` of every frame and pixel for per-pixel thresholds ``(P,)`` (or scalars).

    ``M = lead + sum over segments of share * exp(theta_on on - theta_off off)``, at least the
    lead share and never zero (a segment's weight is positive). The derivatives cost twice the
    value again: only when asked.
    """
    frames, count = events.frames, events.pixels
    pixel = events.segment_pixel
    theta_on = np.broadcast_to(np.asarray(theta_on, np.float64), (count,))
    theta_off = np.broadcast_to(np.asarray(theta_off, np.float64), (count,))
    weight = events.segment_share * np.exp(
        theta_on[pixel] * events.segment_on - theta_off[pixel] * events.segment_off
    )
    size = frames * count
    total = np.bincount(events.segment_key, weights=weight, minlength=size).reshape(frames, count)
    total += events.lead_share
    if not derivatives:
        return LogBlur(np.log(total))
    on = np.bincount(events.segment_key, weights=weight * events.segment_on, minlength=size)
    off = np.bincount(events.segment_key, weights=weight * events.segment_off, minlength=size)
    return LogBlur(
        np.log(total), on.reshape(frames, count) / total, -off.reshape(frames, count) / total
    )
