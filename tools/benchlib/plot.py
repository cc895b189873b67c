"""The speed-against-error plot, drawn with OpenCV: a score against training time (log scale)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from benchlib.results import RunRow

__all__ = [
    "PALETTE",
    "Series",
    "axis_position",
    "draw_speed_error",
    "nice_ticks",
    "speed_error_figure",
    "write_png",
]

PALETTE = (
    (180, 119, 31),
    (14, 127, 255),
    (44, 160, 44),
    (40, 39, 214),
    (189, 103, 148),
    (75, 86, 140),
    (194, 119, 227),
    (127, 127, 127),
    (34, 189, 188),
    (207, 190, 23),
)
"""Line colours (BGR), one per series in order; markers distinguish presets."""

MARGIN = (80, 40, 40, 60)  # left, top, right, bottom, pixels
LEGEND_WIDTH = 260
WHITE, BLACK, GREY = (255, 255, 255), (0, 0, 0), (220, 220, 220)
FONT = cv2.FONT_HERSHEY_SIMPLEX


@dataclass(frozen=True)
class Series:
    """One line of the plot.

    Attributes:
        label: legend text.
        points: ``(training seconds, metric)`` pairs; NaN metrics are skipped.
        marker: ``circle``, ``square`` or ``triangle``.
    """

    label: str
    points: tuple[tuple[float, float], ...]
    marker: str = "circle"


def axis_position(
    value: float, low: float, high: float, start_px: int, end_px: int, log: bool = False
) -> int:
    """Pixel coordinate of ``value`` on an axis running from ``low`` (at ``start_px``) to ``high``.

    With ``log`` the axis is logarithmic (``low`` and ``high`` must then be positive).
    """
    if log:
        value, low, high = math.log10(value), math.log10(low), math.log10(high)
    fraction = 0.5 if high == low else (value - low) / (high - low)
    return int(round(start_px + fraction * (end_px - start_px)))


def nice_ticks(low: float, high: float, log: bool) -> list[float]:
    """Tick values inside ``[low, high]``: 1-2-5 steps (about 6 ticks); 1, 2, 5 per decade (log)."""
    if log:
        decades = range(math.floor(math.log10(low)), math.ceil(math.log10(high)) + 1)
        candidates = [m * 10.0**d for d in decades for m in (1, 2, 5)]
        return [t for t in candidates if low <= t <= high]
    raw = (high - low) / 6 or 1.0
    magnitude = 10 ** math.floor(math.log10(raw))
    step = min((m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= raw), default=raw)
    first = math.ceil(low / step)
    return [float(i * step) for i in range(first, math.floor(high / step + 1e-9) + 1)]


def _marker(image: np.ndarray, centre: tuple[int, int], shape: str, colour) -> None:
    x, y = centre
    if shape == "square":
        cv2.rectangle(image, (x - 5, y - 5), (x + 5, y + 5), colour, -1)
    elif shape == "triangle":
        triangle = np.array([[x, y - 6], [x - 6, y + 5], [x + 6, y + 5]], np.int32)
        cv2.fillPoly(image, [triangle], colour)
    else:
        cv2.circle(image, centre, 5, colour, -1, cv2.LINE_AA)


def _ranges(series: list[Series]) -> tuple[float, float, float, float]:
    points = [p for s in series for p in s.points if math.isfinite(p[1]) and p[0] > 0]
    if not points:
        return 1.0, 10.0, 0.0, 1.0
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return min(xs) / 1.5, max(xs) * 1.5, math.floor(min(ys) - 1), math.ceil(max(ys) + 1)


def draw_speed_error(
    series: list[Series], y_label: str, *, width: int = 1000, height: int = 600, title: str = ""
) -> np.ndarray:
    """An ``(height, width, 3)`` uint8 BGR plot of each series against training time (log s)."""
    image = np.full((height, width, 3), 255, np.uint8)
    left, top = MARGIN[0], MARGIN[1]
    right, bottom = width - LEGEND_WIDTH - MARGIN[2], height - MARGIN[3]
    x_low, x_high, y_low, y_high = _ranges(series)
    for tick in nice_ticks(x_low, x_high, log=True):
        x = axis_position(tick, x_low, x_high, left, right, log=True)
        cv2.line(image, (x, top), (x, bottom), GREY, 1)
        cv2.putText(image, f"{tick:g}", (x - 12, bottom + 20), FONT, 0.45, BLACK, 1, cv2.LINE_AA)
    for tick in nice_ticks(y_low, y_high, log=False):
        y = axis_position(tick, y_low, y_high, bottom, top)
        cv2.line(image, (left, y), (right, y), GREY, 1)
        cv2.putText(image, f"{tick:g}", (left - 45, y + 5), FONT, 0.45, BLACK, 1, cv2.LINE_AA)
    cv2.rectangle(image, (left, top), (right, bottom), BLACK, 1)
    cv2.putText(
        image,
        "training time (s, log scale)",
        ((left + right) // 2 - 110, height - 15),
        FONT,
        0.55,
        BLACK,
        1,
        cv2.LINE_AA,
    )
    cv2.putText(image, y_label, (10, top - 15), FONT, 0.55, BLACK, 1, cv2.LINE_AA)
    cv2.putText(image, title, (left + 150, top - 15), FONT, 0.55, BLACK, 1, cv2.LINE_AA)
    for index, line in enumerate(series):
        colour = PALETTE[index % len(PALETTE)]
        pixels = [
            (
                axis_position(x, x_low, x_high, left, right, log=True),
                axis_position(y, y_low, y_high, bottom, top),
            )
            for x, y in line.points
            if math.isfinite(y) and x > 0
        ]
        if len(pixels) > 1:
            cv2.polylines(image, [np.array(pixels, np.int32)], False, colour, 2, cv2.LINE_AA)
        for pixel in pixels:
            _marker(image, pixel, line.marker, colour)
        legend_y = top + 10 + 22 * index
        _marker(image, (right + 30, legend_y), line.marker, colour)
        cv2.putText(
            image, line.label, (right + 45, legend_y + 5), FONT, 0.45, BLACK, 1, cv2.LINE_AA
        )
    return image


MARKERS = {"fast": "circle", "balanced": "square", "paper": "triangle"}
"""Marker of each preset's series (others: circle)."""


def speed_error_figure(rows: list[RunRow], session: str) -> np.ndarray:
    """HDR PSNR (top) and novel-exposure PSNR (bottom) against training time, one line per
    preset/variant run on ``session`` with the default seed."""
    runs: dict[tuple[str, str], list[RunRow]] = {}
    for row in rows:
        if row.session == session and row.ok and not row.seed and not row.step_cap:
            runs.setdefault((row.preset, row.variant), []).append(row)
    height = max(600, 100 + 22 * len(runs))
    panels = []
    for attribute, label in (
        ("hdr_psnr", "HDR PSNR (dB)"),
        ("novel_psnr", "novel-exposure PSNR (dB)"),
    ):
        series = [
            Series(
                f"{preset} / {variant}",
                tuple(
                    (r.train_s, getattr(r, attribute))
                    for r in sorted(found, key=lambda r: r.budget_s)
                ),
                MARKERS.get(preset, "circle"),
            )
            for (preset, variant), found in sorted(runs.items())
        ]
        panels.append(draw_speed_error(series, label, height=height, title=f"session {session}"))
    return np.vstack(panels)


def write_png(path: Path, image: np.ndarray) -> None:
    """Write a BGR image as PNG (folders created).

    Raises:
        OSError: OpenCV could not write the file.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), image):
        raise OSError(f"{path}: OpenCV could not write the PNG; check the folder is writable")
