"""Frame/event consistency: thresholds, inverse response and pixel factors that explain both.

Between consecutive exposure starts, a pixel's events give the change of its ln intensity;
its two frames give, through the inverse response ``g``, each exposure's blur term
(:mod:`davis_io.calibration.pixel_events`) and its length ``T``, the same change. For every
pixel pair of consecutive frames whose values are both usable:

    ln g(v_(k+1)) - ln g(v_k) = theta_on N_on - theta_off N_off + ln M_(k+1) - ln M_k
                                + ln T_(k+1) - ln T_k.

(A frame gathers light for its exposure: under a camera's auto-exposure, consecutive frames of
the same light differ by the ratio of their exposures.)

A free ``g`` could absorb any common scale of the thresholds if the frames were sharp, but
frames integrate *linear* intensity: a blurred edge mixes bright and dark in proportions the
events time, and only the right contrast mixes them as the frame did. Pixels differ in their
thresholds (a spread of several per cent multiplies every count of the ~tens of events between
two frames), so each pixel gets ON and OFF factors of its own; the global thresholds are the
median pixel's. The fit alternates:

1. thresholds by Levenberg-Marquardt on the disagreement in events (``g`` solved linearly
   inside);
2. each pixel's factors by a few Gauss-Newton steps, shrunk towards 1;

and profiles the latency (events moved earlier) on a grid.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from davis_io.calibration.pixel_events import PixelEvents, log_blur
from davis_io.calibration.response_fit import InverseResponse, hat_basis
from davis_io.session.defaults import DEFAULT_THRESHOLD

__all__ = [
    "THRESHOLD_RANGE",
    "ConsistencyProblem",
    "fit_pixel_factors",
    "fit_thresholds",
    "normalise_factors",
    "refine_pixel_factors",
]

KNOTS = 16
"""Knots of the free inverse response."""

_SMOOTHNESS = 1e-3
"""Weight of the curve's second differences against the data (per pair)."""

_DAMPING = 1e-8
"""Levenberg-Marquardt's least damping of the thresholds' steps (relative to the curvature's
diagonal). The disagreement is flat along the thresholds' common scale (:mod:`scale`): on the
emulated room-s22 the curvature there was a ten-thousandth of the largest, so 1e-3 of the
diagonal outweighed it, and each step went only 0.86 of the last's way along the scale (the
fits took 9 to 30 steps, 148 in all, and stopped short of their least); at 1e-8 they took 2 to
9 (29 in all)."""

_MAX_DAMPING = 1e6
"""Damping at which the threshold fit gives up looking for a step that lowers the disagreement."""

_MAX_STEPS = 30
"""Steps of the threshold fit at most."""

_SCALE_PULL = 1e-4
"""Weight of the thresholds' common scale's pull towards the nominal, in events² per unit of
ln(scale)², added to the disagreement the threshold fit minimises. Where frames are too sharp
to pin the scale (:mod:`scale`) the disagreement is flat along it and the fit ran to a bound of
:data:`THRESHOLD_RANGE` (a 1 ms exposure of the emulated room: 2.0, then 0.01, where the
pixels' factors came out flat and were dropped); the pull holds it near the nominal. Where the
blur pins the scale, the disagreement rises by a few per cent of about 1 event² within a
factor of √2, a thousand times the pull's 1e-5: it moves the scale by about a thousandth of
its distance from the nominal."""

_FACTOR_STEPS = 2
"""Gauss-Newton steps on the pixels' factors each time they are fitted. The factors'
correlation with the true pixels' thresholds (ON/OFF), every sensor pixel fitted from 1:
corridor-s16 0.447/0.874 after one step, 0.494/0.886 after two, 0.495/0.886 after three to
six; room-s10 0.716/0.588 from two on. Each step of every pixel's cost corridor-s16 about 4 s
of its 34 s on one core. The subset's factors, fitted again after each latency profile from
where they were, gave the same thresholds to 0.001 on 11 sessions with two steps as with four."""

_FACTOR_PRIOR = 4.0
"""Shrinkage of a pixel's factors towards 1, in squared events (about 4 pairs' worth)."""

THRESHOLD_RANGE = (0.01, 2.0)
"""Contrast thresholds (ln) the fit may try: outside, the disagreement is infinite. A DVS
threshold is a few tenths; without a ceiling a recording whose frames are too sharp to pin the
scale let the search climb to 300 (a 1/16 exposure of the emulated room), where the blur
term's exponentials overflowed and every value after was NaN."""

_INSIDE = 1.01
"""How far inside :data:`THRESHOLD_RANGE` a start outside it is moved, as a factor."""

_FACTOR_RANGE = (0.05, 3.0)
"""Bounds of a pixel's factor. Spread is absolute, not relative: an OFF threshold of 0.19 drawn
with a spread of 0.06 puts one pixel in 200 below a quarter of the median. Clipped at 0.3, those
pixels kept residuals of tens of events, which ruled the squared disagreement and pulled both
thresholds 26-32 % low (3.1 events RMS against 0.7 at the true values)."""


@dataclass
class ConsistencyProblem:
    """The usable pairs of some pixels, ready for repeated evaluation.

    Attributes:
        events: the pixels' events.
        values: ``(F, P)`` normalised frame values of the pixels.
        usable: ``(F-1, P)`` both frames of the pair lie in the usable range.
        knots: knots of the free inverse response.
        factor_on: ``(P,)`` the pixels' ON factors (ones until fitted); ``factor_off`` OFF.
        log_exposure: ``(F,)`` ln of each frame's exposure time.
        linear_black: None for a free response; else the black level of a linear one.
        latency_us: how much earlier the events were moved.
    """

    events: PixelEvents
    values: np.ndarray
    usable: np.ndarray
    knots: np.ndarray
    factor_on: np.ndarray
    factor_off: np.ndarray
    log_exposure: np.ndarray
    linear_black: float | None = None
    latency_us: int = 0

    def __post_init__(self) -> None:
        self._frame, self._pixel = np.nonzero(self.usable)

    @cached_property
    def _design(self) -> np.ndarray:
        """``(Q, K-1)`` each usable pair's basis difference (the first knot's column dropped)."""
        after = hat_basis(self.values[self._frame + 1, self._pixel], self.knots)
        before = hat_basis(self.values[self._frame, self._pixel], self.knots)
        return (after - before)[:, 1:]

    @cached_property
    def _normal(self) -> np.ndarray:
        """The smoothed normal matrix of the free response's least squares."""
        second = np.diff(np.eye(len(self.knots)), 2, axis=0)[:, 1:]
        normal = self._design.T @ self._design
        return normal + _SMOOTHNESS * len(self._design) * second.T @ second / len(self.knots)

    @property
    def pairs(self) -> int:
        """Number of usable pairs."""
        return len(self._frame)

    def event_change(self, theta_on: float, theta_off: float) -> tuple[np.ndarray, np.ndarray]:
        """The change the events give for each usable pair, and the blur term ``ln M`` (F, P)."""
        on, off = theta_on * self.factor_on, theta_off * self.factor_off
        blur = log_blur(self.events, on, off).value
        return self._change(on, off, blur), blur

    def _change(self, on: np.ndarray, off: np.ndarray, blur: np.ndarray) -> np.ndarray:
        """Each usable pair's change from the pixels' thresholds and the blur term ``(F, P)``."""
        frame, pixel = self._frame, self._pixel
        change = on[pixel] * self.events.between_on[frame, pixel]
        change -= off[pixel] * self.events.between_off[frame, pixel]
        change += blur[frame + 1, pixel] - blur[frame, pixel]
        change += self.exposure_change[frame]
        return change

    @cached_property
    def exposure_change(self) -> np.ndarray:
        """``(F-1,)`` ln of each consecutive pair's exposure ratio (zeros at one exposure)."""
        return np.diff(self.log_exposure)

    def solve(self, theta_on: float, theta_off: float) -> tuple[np.ndarray, InverseResponse]:
        """Residuals (ln units) of each usable pair and the inverse response that fits best."""
        change, _ = self.event_change(theta_on, theta_off)
        if self.linear_black is not None:
            response = InverseResponse(self.knots, self._linear_log_exposure())
        else:
            coefficients = np.linalg.solve(self._normal, self._design.T @ change)
            response = InverseResponse(self.knots, np.concatenate([[0.0], coefficients]))
        # ln g(v_(k+1)) - ln g(v_k): the pairs' basis differences times ln g at the knots.
        frame_change = self._design @ response.log_exposure[1:]
        return frame_change - change, response

    def linearised(self, theta_on: float, theta_off: float) -> tuple[np.ndarray, np.ndarray]:
        """The residuals of :meth:`solve` and their derivatives ``(Q, 2)`` by the thresholds.

        The free response is the linear least-squares answer to the events' change, so the
        residual is the change projected off the response's design, and so is its derivative.
        """
        on, off = theta_on * self.factor_on, theta_off * self.factor_off
        blur = log_blur(self.events, on, off, derivatives=True)
        change = self._change(on, off, blur.value)
        events, frame, pixel = self.events, self._frame, self._pixel
        by_on = events.between_on[frame, pixel] + blur.d_on[frame + 1, pixel]
        by_off = -events.between_off[frame, pixel] + blur.d_off[frame + 1, pixel]
        by_on -= blur.d_on[frame, pixel]
        by_off -= blur.d_off[frame, pixel]
        jacobian = np.stack([self.factor_on[pixel] * by_on, self.factor_off[pixel] * by_off], 1)
        if self.linear_black is not None:
            return self._design @ self._linear_log_exposure()[1:] - change, -jacobian
        both = np.column_stack([change, jacobian])
        both -= self._design @ np.linalg.solve(self._normal, self._design.T @ both)
        return -both[:, 0], -both[:, 1:]

    def _linear_log_exposure(self) -> np.ndarray:
        """``ln(v - black)`` at the knots, 0 at the first."""
        log_g = np.log(np.maximum(self.knots - self.linear_black, 1e-9))
        return log_g - log_g[0]

    def disagreement(self, theta_on: float, theta_off: float) -> float:
        """Mean squared residual in events (residual over the mean threshold).

        Infinite outside :data:`THRESHOLD_RANGE`, and where the blur term overflows (a pixel
        with hundreds of events in one exposure, at a threshold far above its own).
        """
        low, high = THRESHOLD_RANGE
        if min(theta_on, theta_off) <= low or max(theta_on, theta_off) >= high:
            return float("inf")
        with np.errstate(over="ignore", invalid="ignore"):
            residual, _ = self.solve(theta_on, theta_off)
            value = float(np.mean(residual**2)) / (0.5 * (theta_on + theta_off)) ** 2
        return value if np.isfinite(value) else float("inf")


def fit_thresholds(
    problem: ConsistencyProblem, start: tuple[float, float], tolerance: float = 1e-3
) -> tuple[np.ndarray, float]:
    """ON and OFF thresholds that minimise the disagreement, from ``start``, to ``tolerance``.

    Levenberg-Marquardt on the residuals in events (:meth:`ConsistencyProblem.linearised`);
    a step is taken only where it lowers the disagreement. Nelder-Mead needed about 45
    evaluations per fit, this 2 to 9 steps. The thresholds' common scale is pulled weakly
    towards the nominal (:data:`_SCALE_PULL`).

    A start outside :data:`THRESHOLD_RANGE` (thresholds scaled by their pixels' median
    factors) is moved inside it.

    Returns:
        The thresholds ``(2,)`` and the disagreement there (events squared, without the pull).
    """
    low, high = THRESHOLD_RANGE
    theta = np.clip(np.asarray(start, np.float64), low * _INSIDE, high / _INSIDE)
    best = _pulled_disagreement(problem, theta)
    damping = _DAMPING
    for _step in range(_MAX_STEPS):
        system = _normal_equations(problem, theta)
        if system is None:
            break
        while damping < _MAX_DAMPING:
            step = _damped_step(*system, damping)
            value = _pulled_disagreement(problem, theta + step)
            if value < best:
                break
            damping *= 10
        else:
            break
        theta, best = theta + step, value
        damping = max(damping / 10, _DAMPING)
        if np.max(np.abs(step)) < tolerance / 4:
            break
    return theta, best - _scale_pull(theta)[0] ** 2


def _scale_pull(theta: np.ndarray) -> tuple[float, np.ndarray]:
    """The pull's residual ``sqrt(w) ln(sqrt(ON OFF) / nominal)`` and its slopes ``(2,)``."""
    weight = np.sqrt(_SCALE_PULL)
    residual = weight * (0.5 * float(np.log(theta[0] * theta[1])) - np.log(DEFAULT_THRESHOLD))
    return residual, weight * 0.5 / theta


def _pulled_disagreement(problem: ConsistencyProblem, theta: np.ndarray) -> float:
    """The disagreement plus the scale pull's square (infinite where the disagreement is)."""
    value = problem.disagreement(*theta)
    return value + _scale_pull(theta)[0] ** 2 if np.isfinite(value) else value


def _normal_equations(
    problem: ConsistencyProblem, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """Gauss-Newton's normal matrix and gradient of the residuals over the mean threshold.

    Per pair, with the scale pull's residual added. None where they are not finite (a blur
    term that overflows).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        residual, jacobian = problem.linearised(*theta)
        mean = 0.5 * theta.sum()
        # d(r / mean) / d theta, the mean rising by half of each threshold.
        scaled = residual / mean
        jacobian = jacobian / mean - 0.5 * scaled[:, None] / mean
        normal = jacobian.T @ jacobian / len(scaled)
        gradient = jacobian.T @ scaled / len(scaled)
    pull, slopes = _scale_pull(theta)
    normal += np.outer(slopes, slopes)
    gradient += pull * slopes
    if not (np.all(np.isfinite(normal)) and np.all(np.isfinite(gradient))):
        return None
    return normal, gradient


def _damped_step(normal: np.ndarray, gradient: np.ndarray, damping: float) -> np.ndarray:
    """Levenberg-Marquardt's step: the curvature's diagonal raised by ``damping`` of itself."""
    return -np.linalg.lstsq(normal + damping * np.diag(np.diag(normal)), gradient, rcond=None)[0]


def fit_pixel_factors(
    problem: ConsistencyProblem,
    theta: np.ndarray,
    response: Callable[[np.ndarray], np.ndarray],
    steps: int = _FACTOR_STEPS,
) -> np.ndarray:
    """Fit each pixel's ON and OFF factors in place, then divide them by their medians.

    Each pixel's pairs give its own least-squares problem in two unknowns
    (:func:`refine_pixel_factors`); :func:`normalise_factors` then keeps the thresholds the
    median pixel's.

    Returns:
        The thresholds ``(2,)`` multiplied by the factors' medians.
    """
    refine_pixel_factors(problem, theta, response, steps)
    return normalise_factors(
        problem.factor_on, problem.factor_off, problem.usable.sum(axis=0), theta
    )


def refine_pixel_factors(
    problem: ConsistencyProblem,
    theta: np.ndarray,
    response: Callable[[np.ndarray], np.ndarray],
    steps: int = _FACTOR_STEPS,
) -> None:
    """Gauss-Newton steps on each pixel's ON and OFF factors, shrunk towards 1, in place."""
    events, weight = problem.events, problem.usable.astype(np.float64)
    frame_change = np.diff(response(problem.values).reshape(problem.values.shape), axis=0)
    low, high = _FACTOR_RANGE
    for _ in range(steps):
        on, off = theta[0] * problem.factor_on, theta[1] * problem.factor_off
        blur = log_blur(events, on, off, derivatives=True)
        change = on * events.between_on - off * events.between_off + np.diff(blur.value, axis=0)
        change += problem.exposure_change[:, None]
        residual = frame_change - change
        grad_on = -(events.between_on + np.diff(blur.d_on, axis=0)) * theta[0]
        grad_off = (events.between_off - np.diff(blur.d_off, axis=0)) * theta[1]
        a11 = (weight * grad_on**2).sum(0) + _FACTOR_PRIOR
        a22 = (weight * grad_off**2).sum(0) + _FACTOR_PRIOR
        a12 = (weight * grad_on * grad_off).sum(0)
        b1 = -(weight * grad_on * residual).sum(0) - _FACTOR_PRIOR * (problem.factor_on - 1)
        b2 = -(weight * grad_off * residual).sum(0) - _FACTOR_PRIOR * (problem.factor_off - 1)
        determinant = a11 * a22 - a12**2
        problem.factor_on = np.clip(
            problem.factor_on + (a22 * b1 - a12 * b2) / determinant, low, high
        )
        problem.factor_off = np.clip(
            problem.factor_off + (a11 * b2 - a12 * b1) / determinant, low, high
        )


def normalise_factors(
    factor_on: np.ndarray, factor_off: np.ndarray, pairs: np.ndarray, theta: np.ndarray
) -> np.ndarray:
    """Divide the factors of pixels with three usable ``pairs`` or more by their medians.

    In place; the other pixels' factors are set to 1.

    Returns:
        The thresholds ``(2,)`` multiplied by the medians (unchanged when no pixel has three).
    """
    measured = pairs >= 3
    if not measured.any():
        factor_on[:] = factor_off[:] = 1.0
        return np.asarray(theta, np.float64)
    means = []
    for factors in (factor_on, factor_off):
        mean = float(np.median(factors[measured]))
        factors /= mean
        factors[~measured] = 1.0
        means.append(mean)
    return np.asarray(theta, np.float64) * np.asarray(means)
