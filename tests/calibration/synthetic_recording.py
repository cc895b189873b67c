"""A small recording with exactly known sensor values, made without the emulator's renderer.

A smooth random texture of ln radiance slides sideways past a ``64 x 48`` sensor. Ideal DVS
pixels (each with its own ON and OFF threshold, no lag) fire an event whenever their ln
intensity crosses the next level, stamped at the crossing; frames integrate linear intensity over
each exposure (trapezoid rule on a fine clock) through a chosen response curve and a 10-bit ADC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.calibration import CalibrationInput
from davis_io.emulator import Response

WIDTH, HEIGHT = 64, 48
STEP_US = 250


@dataclass(frozen=True)
class KnownSensor:
    """The sensor values a synthetic recording is made with."""

    threshold_on: float
    threshold_off: float
    spread: float
    response: Response


def _texture(rng: np.random.Generator, length: int) -> np.ndarray:
    """``(HEIGHT, length)`` smooth ln radiance with about 3 natural-log units of contrast."""
    texture = np.zeros((HEIGHT, length))
    x, y = np.arange(length)[None, :], np.arange(HEIGHT)[:, None]
    for _ in range(24):
        fx, fy = rng.uniform(0.02, 0.25), rng.uniform(0.0, 0.2)
        texture += rng.uniform(0.1, 0.35) * np.sin(fx * x + fy * y + rng.uniform(0, 2 * np.pi))
    return texture - texture.mean() - 0.7


def synthetic_recording(
    sensor: KnownSensor,
    frames: int = 8,
    seed: int = 0,
    exposure_us: int = 60_000,
    exposure_steps: tuple[float, ...] = (1.0,),
) -> tuple[CalibrationInput, np.ndarray, np.ndarray]:
    """The recording, and each pixel's true ON and OFF thresholds ``(H, W)``.

    Frames expose every 100 ms, frame ``k`` for ``exposure_us`` (at most 90 ms) times the
    ``k``-th of ``exposure_steps`` in turn, as an auto-exposure sets them: a shorter exposure
    gathers less light. The texture slides 0.25 px per ms with a sway.
    """
    rng = np.random.default_rng(seed)
    interval_us = 100_000
    end_us = frames * interval_us
    times = np.arange(0, end_us + STEP_US, STEP_US)
    shift = 0.25e-3 * times + 6.0 * np.sin(times * 2e-5)
    texture = _texture(rng, int(shift.max()) + WIDTH + 2)
    columns = np.arange(WIDTH)[None, :] + shift[:, None]  # (T, W)
    left = np.floor(columns).astype(int)
    part = columns - left
    log_radiance = np.stack(
        [(1 - p) * texture[:, c] + p * texture[:, c + 1] for c, p in zip(left, part, strict=True)]
    )  # (T, H, W)
    size = (HEIGHT, WIDTH)
    theta_on = np.maximum(rng.normal(sensor.threshold_on, sensor.spread, size), 0.02)
    theta_off = np.maximum(rng.normal(sensor.threshold_off, sensor.spread, size), 0.02)
    events = _ideal_events(log_radiance, times, theta_on, theta_off)
    starts = 10_000 + np.arange(frames) * interval_us
    factors = np.resize(np.asarray(exposure_steps, np.float64), frames)
    durations = np.round(exposure_us * factors).astype(np.int64)
    images = []
    for start, duration, factor in zip(starts, durations, factors, strict=True):
        inside = (times >= start) & (times <= start + duration)
        weights = np.full(inside.sum(), 1.0)
        weights[[0, -1]] = 0.5
        light = np.tensordot(weights / weights.sum(), np.exp(log_radiance[inside]), axes=1)
        linear = factor * light
        noisy = linear * (1 + rng.normal(0, 0.004, size))
        images.append(np.round(np.clip(sensor.response(noisy), 0, 1) * 1023) / 1023)
    recording = CalibrationInput(
        frames=np.stack(images),
        adc_step=1 / 1023,
        times_us=events["t"],
        x=events["x"],
        y=events["y"],
        is_on=events["on"],
        exposure_start_us=starts,
        exposure_end_us=starts + durations,
    )
    return recording, theta_on, theta_off


def _ideal_events(log_radiance, times, theta_on, theta_off) -> np.ndarray:
    """Events of ideal pixels: one per level crossed, stamped where the crossing falls."""
    base = log_radiance[0].copy()
    out = []
    for index in range(1, len(times)):
        previous, current = log_radiance[index - 1], log_radiance[index]
        for sign, theta in ((1, theta_on), (-1, theta_off)):
            while True:
                crossed = sign * (current - base) >= theta
                if not crossed.any():
                    break
                level = base + sign * theta
                rows, cols = np.nonzero(crossed)
                span = current[crossed] - previous[crossed]
                share = np.clip(
                    (level[crossed] - previous[crossed]) / np.where(span, span, 1), 0, 1
                )
                stamp = times[index - 1] + np.round(share * (times[index] - times[index - 1]))
                out.append((stamp.astype(np.int64), cols, rows, np.full(len(rows), sign > 0)))
                base[crossed] = level[crossed]
    t, x, y, on = (np.concatenate(parts) for parts in zip(*out, strict=True))
    order = np.argsort(t, kind="stable")
    events = np.empty(len(t), [("t", "i8"), ("x", "u2"), ("y", "u2"), ("on", "?")])
    events["t"], events["x"], events["y"], events["on"] = t[order], x[order], y[order], on[order]
    return events
