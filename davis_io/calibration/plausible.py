"""What a DAVIS can physically have, and the record of what a calibration had to assume.

Every value the calibration estimates is checked before it is used: an estimate at its search's
bound, outside these ranges, or from a profile too flat to locate anything is not a measurement.
It is reported and stored as assumed (with the reason), and the nominal value stands in for it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from davis_io.session.bounds import Bounds

__all__ = [
    "BLACK_LEVEL",
    "DEAD_TIME_US",
    "FACTOR_SPREAD",
    "FLAT_PROFILE",
    "LATENCY_US",
    "THRESHOLD",
    "THRESHOLD_SCALE",
    "Assumptions",
    "flat_profile",
]

THRESHOLD = Bounds(0.05, 1.0, "ln per event")
"""A DAVIS pixel's contrast threshold: a few tenths at usual biases, 0.05-1 at the extremes."""

THRESHOLD_SCALE = Bounds(0.5, 2.0, "of the nominal threshold")
"""How far a DAVIS's thresholds lie from the nominal 0.3: 0.15 to 0.6 at usual biases."""

LATENCY_US = Bounds(0, 40_000, "µs", integer=True)
"""How late a DAVIS pixel's events come: well under a millisecond in bright light, a few in the
dark; tens of milliseconds in near darkness, where the photoreceptor's bandwidth falls to tens of
hertz."""

DEAD_TIME_US = Bounds(0, 20_000, "µs", integer=True)
"""A pixel's refractory period: microseconds to a few milliseconds."""

FACTOR_SPREAD = Bounds(0.005, 0.4, "of the median")
"""The spread (standard deviation) of the pixels' threshold factors: a few per cent of pixel
mismatch. Under half a per cent the factors did not move from their prior of 1: the recording
does not tell the pixels apart."""

BLACK_LEVEL = Bounds(0.0, 0.5, "of full scale", high_open=True)
"""A raw frame's value with no light: the ADC's offset, a few per cent of full scale."""

FLAT_PROFILE = 0.01
"""A profile whose values differ by less than this fraction of their smallest is flat: it
locates nothing."""


def flat_profile(costs: np.ndarray) -> bool:
    """True when the finite ``costs`` of a profile vary by under :data:`FLAT_PROFILE`."""
    finite = np.asarray(costs, np.float64)
    finite = finite[np.isfinite(finite)]
    if len(finite) < 2:
        return True
    return float(finite.max() - finite.min()) < FLAT_PROFILE * max(float(finite.min()), 1e-12)


class Assumptions:
    """The values a calibration could not measure, each with its reason, said once as it goes.

    Args:
        progress: receives one line per assumption.
    """

    def __init__(self, progress: Callable[[str], None]):
        self.reasons: dict[str, str] = {}
        self._progress = progress

    def add(self, name: str, reason: str, instead: str) -> None:
        """Record that ``name`` was not measured (``reason``) and ``instead`` stands for it."""
        self.reasons[name] = f"{reason}; {instead}"
        self._progress(f"{name} not measured ({reason}): {instead}")

    def __contains__(self, name: str) -> bool:
        return name in self.reasons

    def check(self, name: str, value, bounds: Bounds, instead: str) -> bool:
        """Record ``name`` as assumed unless ``value`` lies in ``bounds``; True when it does."""
        if bounds.holds(value):
            return True
        self.add(name, f"{value:g} is outside what a DAVIS can have ({bounds.describe()})", instead)
        return False
