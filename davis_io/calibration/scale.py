"""The thresholds' common scale: whether the recording pins it, and how tightly.

Frame/event consistency fixes the ratio of the ON and OFF thresholds in any recording, but
their common scale only where something breaks the symmetry of scaling the thresholds and the
free inverse response together. A known response shape would, but the shape cannot be told
without the scale (a gamma curve is a power law in the dark, as straight in log-log as a linear
APS). Blur does: frames integrate linear intensity, so only the right contrast mixes bright and
dark at a blurred edge as the frame did. Short exposures leave the scale free: the disagreement
is then flat along it, and the minimiser wanders (to twice the truth, or to nothing).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from davis_io.calibration.consistency import ConsistencyProblem
from davis_io.session.defaults import DEFAULT_THRESHOLD

__all__ = [
    "MEASURED_RISE",
    "SCALES",
    "CommonScale",
    "ScaleProfile",
    "common_scale",
    "scale_profile",
]

SCALES = np.geomspace(0.5, 2.0, 9)
"""Common scales of the thresholds the profile tries (the fit's own, 1, at the middle)."""

MEASURED_RISE = 0.015
"""The disagreement must rise by this fraction (of its value at the fit) within a factor of
√2 of the fitted scale on both sides for the scale to count as measured. Measured at x0.71 and
x1.41 on emulated recordings, each read from the drawn subset of pairs the fit reads (three
draws where close): a linear sensor at 150 ms exposures (`room-s22`) 1.9-2.6 %, its fitted
scale 0-3 % under the truth; 20 ms exposures every 200 ms (`lamp-s102`) 1.9-2.8 %, 4-8 % over;
the default room at 256 ms 14-18 %; 16 ms exposures 0.9-1.2 %, a minimum at 2.2 times the
truth; 1 ms exposures 0.0-0.1 %. At 2 % (before) a draw of `room-s22`'s pixels left the scale
free, and the nominal 0.3 put its thresholds 63 % over the truth."""

PINNED_RISE = 0.02
"""The rise that bounds the scale's uncertainty: within a factor of √2 of the fit on
emulated recordings, the scales whose disagreement rose less than this held the truth (two
standard uncertainties)."""


@dataclass(frozen=True)
class ScaleProfile:
    """The disagreement along the thresholds' common scale.

    Attributes:
        scales: ``(S,)`` factors applied to both thresholds.
        rise: ``(S,)`` the disagreement there over its value at the fit, minus one.
    """

    scales: np.ndarray
    rise: np.ndarray

    def interval(self, rise: float = PINNED_RISE) -> tuple[float, float]:
        """The smallest and largest scale whose disagreement rises less than ``rise``.

        Every scale where no disagreement is finite (not even the fit's): nothing tells them
        apart.
        """
        inside = self.scales[self.rise < rise]
        if not len(inside):
            inside = self.scales
        return float(inside.min()), float(inside.max())

    @property
    def pinned(self) -> bool:
        """The scale is measured: the disagreement rises by MEASURED_RISE within √2 each side."""
        low, high = self.interval(MEASURED_RISE)
        return low > 1 / np.sqrt(2) + 1e-9 and high < np.sqrt(2) - 1e-9

    def half_width(self) -> float:
        """Half the range of ln(scale) over which the disagreement rises under PINNED_RISE.

        From a parabola in ln(scale) through the finite points within a factor of √2 of the
        fit (where the profile is nearly quadratic); infinite when it does not curve up. Two
        standard uncertainties of the scale: on the emulated recordings the truth lay inside.
        """
        log_scale = np.log(self.scales)
        near = (np.abs(log_scale) <= np.log(np.sqrt(2)) + 1e-9) & np.isfinite(self.rise)
        if near.sum() < 3:
            return float("inf")
        curvature = float(np.polyfit(log_scale[near], self.rise[near], 2)[0])
        return float(np.sqrt(PINNED_RISE / curvature)) if curvature > 0 else float("inf")

    def describe(self) -> str:
        """One line: the rise at each scale."""
        pairs = zip(self.scales, self.rise, strict=True)
        return ", ".join(f"x{scale:.2f}: {100 * rise:+.1f} %" for scale, rise in pairs)


def scale_profile(problem: ConsistencyProblem, theta: np.ndarray) -> ScaleProfile:
    """The disagreement of ``problem`` with both thresholds scaled, the response re-solved."""
    disagreement = np.array([problem.disagreement(*(scale * theta)) for scale in SCALES])
    rise = disagreement / disagreement[len(SCALES) // 2] - 1
    return ScaleProfile(SCALES.copy(), np.maximum(rise, 0.0))


@dataclass(frozen=True)
class CommonScale:
    """The thresholds once their common scale is settled.

    Attributes:
        theta: ``(2,)`` ON and OFF thresholds.
        measured: the blur pins the scale; else it is the nominal
            :data:`~davis_io.session.DEFAULT_THRESHOLD` and only the ratio is measured.
        width: the scale's standard uncertainty, relative: half of :meth:`ScaleProfile.half_width`
            where measured, half the range of scales the recording cannot tell apart where not.
    """

    theta: np.ndarray
    measured: bool
    width: float = 0.0


def common_scale(
    problem: ConsistencyProblem, theta: np.ndarray, progress: Callable[[str], None]
) -> CommonScale:
    """The fitted thresholds where the blur pins their scale, else the nominal scale."""
    profile = scale_profile(problem, theta)
    progress(f"common scale {'pinned' if profile.pinned else 'free'}: {profile.describe()}")
    if profile.pinned:
        return CommonScale(theta, True, profile.half_width() / 2)
    low, high = profile.interval()
    progress(
        "the thresholds' common scale is not measurable here (frames too sharp): nominal "
        f"{DEFAULT_THRESHOLD}, their ratio measured; give --threshold if it is known"
    )
    return CommonScale(theta * DEFAULT_THRESHOLD / np.sqrt(theta.prod()), False, (high - low) / 2)
