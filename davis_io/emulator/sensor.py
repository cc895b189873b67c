"""The emulated camera's sensor: DVS pixel model, APS response, colour filter and event latency.

A sensor is either the default one a recording's settings name (a DVS preset, a response curve,
a colour filter) or one drawn at random from a seed, so that a fit can be measured on a sensor
it was not tuned to. Its values go only into the session's ``truth/`` (``sensor``), never into
``session.json``: the pipeline has to measure them, as it would on a real camera.

Random draws (every range inclusive, each value independent):

* ON and OFF thresholds in 0.15-0.5, per-pixel spread 0.02-0.06;
* refractory period: none with probability 1/3, else 0.1-1 ms;
* photoreceptor cutoff: fast (2-5 kHz, no visible lag) with probability 1/3, else 60-400 Hz,
  scaled by the pixel's light, so dark pixels lag by milliseconds;
* leak 0.01-0.2 Hz and shot noise 0.05-2 Hz per pixel, leak spread 0-0.2 decades;
* latency 0-3 ms; the one-step delay of See-NeRF's pixel model or none;
* response: ``linear`` (black level 0.01-0.08, slope 0.2-0.5, saturation 0.85-0.98),
  ``reinhard_gamma`` (gain 0.5-2, gamma 1.8-2.6), ``film`` (midpoint 0.2-0.6, width 0.8-1.4)
  or ``s_curve`` (gain 0.5-2, gamma 1.8-2.6, contrast 1.3-2.0);
* colour filter: monochrome or RGGB.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from davis_io.emulator.dvs import DVS_PRESETS, DvsParams, DvsPixels
from davis_io.emulator.response import RESPONSE_CURVES, Response
from davis_io.errors import UsageError
from davis_io.types import ColorFilter

__all__ = ["SENSOR_KINDS", "Sensor", "draw_sensor"]

SENSOR_KINDS = ("default", "random")
"""``default``: the sensor the settings name; ``random``: one drawn from the seed."""


@dataclass(frozen=True)
class Sensor:
    """Everything about the emulated pixels that a real camera would not state.

    Attributes:
        dvs: the DVS pixel model.
        response: the APS response curve.
        color_filter: colour filter of APS and DVS pixels.
        latency_us: how much later than the light the DVS pixels see it, µs.
    """

    dvs: DvsParams
    response: Response
    color_filter: ColorFilter
    latency_us: int = 0

    def step_delay_us(self, step_us: int) -> int:
        """How late a pixel fires by its one-step delay, at DVS steps of ``step_us``."""
        return step_us if self.dvs.one_step_delay and self.dvs.cutoff_hz > 0 else 0

    def dead_time_us(self, step_us: int) -> int:
        """Shortest interval between the events of a pixel that must fire many times in a row.

        Its refractory period, or one DVS step of ``step_us`` when that is longer: the events a
        pixel owes share the step's sub-steps, so one held back by its refractory period fires
        again in a later step.
        """
        return max(self.dvs.refractory_us, step_us) if self.dvs.refractory_us > 0 else 0

    def with_noise_scaled(self, scale: float) -> Sensor:
        """The same sensor with its DVS leak and shot-noise rates times ``scale``."""
        if scale == 1.0:
            return self
        dvs = dataclasses.replace(
            self.dvs,
            leak_rate_hz=self.dvs.leak_rate_hz * scale,
            shot_noise_rate_hz=self.dvs.shot_noise_rate_hz * scale,
        )
        return dataclasses.replace(self, dvs=dvs)

    def to_json(self, pixels: DvsPixels | None = None, step_us: int = 0) -> dict:
        """JSON-safe values; with the drawn ``pixels``, their thresholds' median and harmonic mean.

        A calibration measures the median pixel's threshold; the harmonic mean is the one a
        count stands for on average (a change ``d`` gives ``d / theta`` events at a pixel of
        threshold ``theta``). ``event_delay_us`` adds to the latency the one DVS step of
        ``step_us`` by which a one-step-delay pixel fires late (the low-pass lag, which depends
        on the light, is not in it); ``dead_time_us`` is :meth:`dead_time_us`.
        """
        out = {
            "dvs": dataclasses.asdict(self.dvs),
            "response": self.response.to_json(),
            "color_filter": self.color_filter.value,
            "latency_us": self.latency_us,
            "event_delay_us": self.latency_us + self.step_delay_us(step_us),
            "dead_time_us": self.dead_time_us(step_us),
        }
        if pixels is not None:
            for name, values in (("on", pixels.threshold_on), ("off", pixels.threshold_off)):
                values = np.asarray(values, np.float64)
                out[f"median_threshold_{name}"] = float(np.median(values))
                out[f"harmonic_threshold_{name}"] = float(1.0 / np.mean(1.0 / values))
        return out


def default_sensor(dvs_preset: str, response: str, color_filter: ColorFilter) -> Sensor:
    """The sensor named by a preset, a response curve and a colour filter.

    Raises:
        UsageError: an unknown preset or curve.
    """
    if dvs_preset not in DVS_PRESETS:
        raise UsageError(f"DVS preset {dvs_preset!r} is not one of {', '.join(DVS_PRESETS)}")
    if response not in RESPONSE_CURVES:
        raise UsageError(f"response {response!r} is not one of {', '.join(RESPONSE_CURVES)}")
    return Sensor(DVS_PRESETS[dvs_preset], RESPONSE_CURVES[response], color_filter)


def _draw_response(rng: np.random.Generator) -> Response:
    family = str(rng.choice(["linear", "reinhard_gamma", "film", "s_curve"]))
    if family == "linear":
        return Response(
            "linear",
            black=rng.uniform(0.01, 0.08),
            slope=rng.uniform(0.2, 0.5),
            saturation=rng.uniform(0.85, 0.98),
        )
    if family == "film":
        return Response("film", midpoint=rng.uniform(0.2, 0.6), width=rng.uniform(0.8, 1.4))
    gain, gamma = rng.uniform(0.5, 2.0), rng.uniform(1.8, 2.6)
    if family == "s_curve":
        return Response("s_curve", gain=gain, gamma=gamma, contrast=rng.uniform(1.3, 2.0))
    return Response("reinhard_gamma", gain=gain, gamma=gamma)


def _draw_dvs(rng: np.random.Generator) -> DvsParams:
    base = DVS_PRESETS["noisy"]
    fast = rng.random() < 1 / 3
    return dataclasses.replace(
        base,
        threshold_on=rng.uniform(0.15, 0.5),
        threshold_off=rng.uniform(0.15, 0.5),
        threshold_sigma=rng.uniform(0.02, 0.06),
        cutoff_hz=rng.uniform(2000, 5000) if fast else rng.uniform(60, 400),
        leak_rate_hz=rng.uniform(0.01, 0.2),
        shot_noise_rate_hz=rng.uniform(0.05, 2.0),
        refractory_us=0 if rng.random() < 1 / 3 else int(rng.uniform(100, 1000)),
        rate_cov_decades=rng.uniform(0.0, 0.2),
        one_step_delay=bool(rng.random() < 0.5),
    )


def draw_sensor(seed: int) -> Sensor:
    """A random sensor (the ranges in the module docstring), the same for the same seed."""
    rng = np.random.default_rng([seed, 0x5E45])
    dvs = _draw_dvs(rng)
    response = _draw_response(rng)
    color_filter = ColorFilter.MONO if rng.random() < 0.5 else ColorFilter.RGGB
    return Sensor(dvs, response, color_filter, latency_us=int(rng.uniform(0, 3000)))
