"""``SensorCalibration``: the sensor's facts measured from a recording, and their HDF5 group.

A real DAVIS states its biases, not what they do: its pixels' effective contrast thresholds,
their spread, how late the events come and what the APS response is. These are measured from
the session itself (``davis_io.calibration``) and stored in ``session.h5`` under
``/calibration``; poses and fits read them from there. Layout::

    /calibration            attrs: JSON ``facts`` (every scalar field below)
        response_value         float64 (K,)   normalised frame values, increasing
        response_log_exposure  float64 (K,)   ln(relative exposure) at those values
        pixel_factor_on        float32 (H, W) each pixel's ON threshold / threshold_on
        pixel_factor_off       float32 (H, W) each pixel's OFF threshold / threshold_off
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

import h5py
import numpy as np

from davis_io.errors import SessionError

__all__ = [
    "CALIBRATION_PATH",
    "SensorCalibration",
    "default_calibration",
    "read_calibration",
    "write_calibration",
]

CALIBRATION_PATH = "/calibration"
_ARRAYS = ("response_value", "response_log_exposure", "pixel_factor_on", "pixel_factor_off")
_THRESHOLD_VALUES = ("thresholds", "threshold_scale", "pixel_factors")
"""The assumed values a stated threshold replaces."""


@dataclass(frozen=True)
class SensorCalibration:
    """What the pixels of one recording do, as measured (or given, or true).

    Attributes:
        threshold_on: ON contrast threshold of the median pixel: ln intensity change per ON
            event (a pixel's own is ``threshold_on * pixel_factor_on``).
        threshold_off: the same for OFF events.
        threshold_on_sd: standard uncertainty of ``threshold_on``.
        threshold_off_sd: the same for ``threshold_off``.
        latency_us: how much later than the light change its events come, µs (the pixel's
            delay and the transport's together; bins cut the events this much later).
        black_level: normalised frame value of no light.
        saturation: normalised frame value where the APS clips (1 if it never does).
        response_linear: frames are linear in exposure above the black level, as a raw DAVIS
            frame is (the free curve is a straight line in ln(v - black)).
        cutoff_hz: the photoreceptor's cut-off frequency in bright light, or 0 when unknown.
        dead_time_us: the shortest time between two events of a pixel that must fire many
            times in a row (its refractory period), µs; 0 when unknown.
        noise_gain: linear frames' noise variance per unit of value above the black level
            (their shot noise), normalised units; 0 when not measured.
        noise_floor: their noise variance at the black level (read noise and rounding).
        response_value: ``(K,)`` increasing normalised frame values of the inverse response.
        response_log_exposure: ``(K,)`` ln(relative exposure) at those values, increasing.
        pixel_factor_on: ``(H, W)`` each pixel's ON threshold over ``threshold_on`` (median
            1); ones when not measured.
        pixel_factor_off: the same for OFF.
        residual_events: RMS disagreement of frames and events after the fit, in events.
        pairs: consecutive-frame pixel pairs the fit used.
        source: ``measured``, ``measured ratio, nominal scale`` (frames too sharp for the blur
            to pin the scale: the thresholds' ratio and pixel factors are measured, their common
            scale is :data:`~davis_io.session.DEFAULT_THRESHOLD`), ``measured ratio, linear
            frames scale`` (as before, the scale read from frames linear in exposure, the
            response held to their line), ``assumed`` (the thresholds
            could not be measured: the nominal ones, with a wide uncertainty), ``given``,
            ``truth`` or ``default`` (nothing could be measured).
        method: one line saying how the values were found.
        assumed: the values that were not measured, each with why (an estimate at its search's
            bound, outside what a DAVIS can have, from a flat profile, or no data for it): a
            prior (the nominal value) stands in for each, which later stages treat as such.
            Keys are field names (``thresholds``, ``threshold_scale``, ``pixel_factors``,
            ``latency_us``, ``dead_time_us``, ``black_level``, ``saturation``, ``response``).
    """

    threshold_on: float
    threshold_off: float
    threshold_on_sd: float = 0.0
    threshold_off_sd: float = 0.0
    latency_us: int = 0
    black_level: float = 0.0
    saturation: float = 1.0
    response_linear: bool = False
    cutoff_hz: float = 0.0
    dead_time_us: int = 0
    noise_gain: float = 0.0
    noise_floor: float = 0.0
    response_value: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    response_log_exposure: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    pixel_factor_on: np.ndarray = dataclasses.field(default_factory=lambda: np.ones((0, 0)))
    pixel_factor_off: np.ndarray = dataclasses.field(default_factory=lambda: np.ones((0, 0)))
    residual_events: float = float("nan")
    pairs: int = 0
    source: str = "measured"
    method: str = ""
    assumed: dict[str, str] = dataclasses.field(default_factory=dict)

    @property
    def thresholds_measured(self) -> bool:
        """The thresholds (their scale included) were measured from the recording or stated."""
        return "thresholds" not in self.assumed and "threshold_scale" not in self.assumed

    @property
    def threshold(self) -> float:
        """The mean of the ON and OFF thresholds (one number for the event model's units)."""
        return 0.5 * (self.threshold_on + self.threshold_off)

    @property
    def noise_offset(self) -> float:
        """Linear frames' value above black where shot noise equals read noise (0: unmeasured)."""
        return self.noise_floor / self.noise_gain if self.noise_gain > 0 else 0.0

    def with_threshold(self, threshold: float) -> SensorCalibration:
        """This calibration with one stated threshold for ON and OFF and every pixel."""
        return dataclasses.replace(
            self,
            threshold_on=float(threshold),
            threshold_off=float(threshold),
            threshold_on_sd=0.0,
            threshold_off_sd=0.0,
            pixel_factor_on=np.ones((0, 0)),
            pixel_factor_off=np.ones((0, 0)),
            source="given",
            assumed={
                name: why for name, why in self.assumed.items() if name not in _THRESHOLD_VALUES
            },
        )

    def facts(self) -> dict:
        """The scalar fields, JSON-safe."""
        return {
            f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in _ARRAYS
        }

    def summary(self) -> str:
        """A few human-readable lines."""
        lines = [
            f"thresholds ON {self.threshold_on:.3f} ± {self.threshold_on_sd:.3f}, "
            f"OFF {self.threshold_off:.3f} ± {self.threshold_off_sd:.3f} ({self.source})",
            f"event latency {self.latency_us / 1000:.1f} ms; frames black at "
            f"{self.black_level:.3f}, clip at {self.saturation:.3f}, response "
            + ("linear" if self.response_linear else "not linear"),
        ]
        if self.dead_time_us:
            lines.append(
                f"pixel dead time {self.dead_time_us / 1000:.2f} ms (at most "
                f"{1e6 / self.dead_time_us:.0f} events per second from one pixel)"
            )
        if self.noise_gain > 0:
            lines.append(
                f"frame noise: variance {self.noise_gain:.2e} x (value - black) + "
                f"{self.noise_floor:.2e} (shot noise equals read noise "
                f"{self.noise_offset:.4f} above black)"
            )
        if self.pixel_factor_on.size:
            spread = np.std(np.concatenate([self.pixel_factor_on, self.pixel_factor_off], None))
            lines.append(f"pixel threshold spread {100 * spread:.1f} %")
        if self.pairs:
            lines.append(
                f"frames and events agree to {self.residual_events:.2f} events RMS over "
                f"{self.pairs} pixel pairs"
            )
        lines += [f"assumed {name}: {why}" for name, why in self.assumed.items()]
        return "\n".join(lines) + (f"\nmethod: {self.method}" if self.method else "")


def default_calibration(threshold: float, why: str) -> SensorCalibration:
    """The nominal sensor, when nothing could be measured (``why`` says what was missing)."""
    return SensorCalibration(threshold, threshold, source="default", method=why)


def write_calibration(h5: h5py.File, calibration: SensorCalibration) -> None:
    """Store ``calibration`` in an open, writable ``session.h5`` (replacing any)."""
    if CALIBRATION_PATH in h5:
        del h5[CALIBRATION_PATH]
    group = h5.create_group(CALIBRATION_PATH)
    group.attrs["facts"] = json.dumps(calibration.facts())
    for name in _ARRAYS:
        group.create_dataset(name, data=getattr(calibration, name), compression="gzip")


def read_calibration(h5: h5py.File) -> SensorCalibration | None:
    """The stored calibration, or None when the session has none.

    Raises:
        SessionError: the group is there but unreadable (names what to do).
    """
    group = h5.get(CALIBRATION_PATH)
    if group is None:
        return None
    try:
        facts = json.loads(group.attrs["facts"])
        arrays = {name: group[name][()] for name in _ARRAYS}
        return SensorCalibration(**facts, **arrays)
    except (KeyError, TypeError, json.JSONDecodeError) as error:
        raise SessionError(
            f"{h5.filename}: /calibration is unreadable ({error}); run "
            "`seecap calibrate SESSION --force` to measure it again"
        ) from None
