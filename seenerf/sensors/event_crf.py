"""The event response (eqs. 9-12): filter channel, delay low-pass, counts = log change / Theta.

Beyond the paper, a pixel's dead time: one that owes more events than its refractory period
lets it fire within a step fires what it can and owes the rest to the next steps
(:func:`rate_limited`); with sub-frames the steps are finer than the bins, so an edge that
crosses the pixel early in a bin is owed from then on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn

from davis_io.session import DEFAULT_THRESHOLD
from seenerf.sensors.rgb_crf import warm_start_module

__all__ = [
    "DELAY_FACTORS",
    "EventCrf",
    "EventModelSpec",
    "event_log_radiance",
    "low_pass",
    "predicted_counts",
    "rate_limited",
    "v2e_intensity_factor",
]

_LOG_LIMIT = 60.0


def event_log_radiance(log_radiance: torch.Tensor, mix: torch.Tensor) -> torch.Tensor:
    """Log radiance an event pixel sees: ``ln(sum_c mix_c exp(logE_c))``.

    With a one-hot Bayer ``mix`` this picks the pixel's own channel; with luminance weights it is
    the log luminance of a monochrome pixel.

    Args:
        log_radiance: ``(R, P, 3)`` log radiance at the exposure's P rendered poses.
        mix: ``(R, 3)`` colour weights of each pixel.

    Returns:
        ``(R, P)``.
    """
    log_mix = torch.log(mix.clamp(min=1e-12))[:, None, :]
    return torch.logsumexp(log_radiance + log_mix, dim=-1)


def low_pass(signal: torch.Tensor, epsilon: torch.Tensor, order: int = 1) -> torch.Tensor:
    """Cascade of ``order`` first-order filters ``s_i = (1 - eps_i) s_(i-1) + eps_i x_i``.

    Args:
        signal: ``(R, P)`` samples at the rendered time points.
        epsilon: ``(R, P)`` filter coefficients in [0, 1] (clamped here); ``epsilon[:, 0]`` unused.
        order: number of cascaded stages (1 reference, 2 v2e and the paper, 4 Deblur-e).

    Returns:
        ``(R, P)`` filtered samples; ``order == 0`` returns the signal unchanged.
    """
    epsilon = epsilon.clamp(0.0, 1.0)
    for _ in range(order):
        states = [signal[:, 0]]
        for index in range(1, signal.shape[1]):
            states.append(
                (1 - epsilon[:, index]) * states[-1] + epsilon[:, index] * signal[:, index]
            )
        signal = torch.stack(states, dim=1)
    return signal


def predicted_counts(filtered_log: torch.Tensor, threshold: float) -> torch.Tensor:
    """Continuous event counts per bin ``(L_(k+1) - L_k) / threshold``, shape ``(R, P-1)``."""
    return torch.diff(filtered_log, dim=1) / threshold


def rate_limited(counts: torch.Tensor, cap_on: torch.Tensor, cap_off: torch.Tensor) -> torch.Tensor:
    """Counts of pixels that fire at most ``cap`` events per step and owe the rest to later steps.

    Args:
        counts: ``(R, S)`` signed counts the light change asks for, step by step.
        cap_on: ``(R,)`` or ``()``: the most ON counts one step can hold.
        cap_off: the same for OFF counts (positive).

    Returns:
        ``(R, S)`` the counts fired; what is still owed after the last step is not in them.
    """
    owed = torch.zeros_like(counts[:, 0])
    fired = []
    for index in range(counts.shape[1]):
        owed = owed + counts[:, index]
        now = torch.maximum(torch.minimum(owed, cap_on), -cap_off)
        owed = owed - now
        fired.append(now)
    return torch.stack(fired, dim=1)


def v2e_intensity_factor(log_exposure: torch.Tensor) -> torch.Tensor:
    """Fixed bandwidth factor of a v2e-style pixel: ``(x / (x + 1))^(1/2.2)``, x = radiance x s."""
    x = torch.exp(log_exposure.clamp(-_LOG_LIMIT, _LOG_LIMIT))
    return (x / (x + 1.0)).clamp(min=1e-12) ** (1 / 2.2)


@dataclass(frozen=True)
class EventModelSpec:
    """How predicted event counts are formed; the named variants are combinations of these.

    Attributes:
        colour: ``filter`` (recorded colour filter) or ``learned`` (learned RGB mix, Ev-DeblurNeRF).
        delay: ``mlp`` (learned f_ev), ``v2e`` (fixed tone-curve factor) or ``none``.
        order: low-pass stages (1 reference, 2 v2e / paper, 4 Deblur-e).
        domain: ``log`` (reference: filter log radiance) or ``linear`` (paper: filter radiance,
            then ln).
        calibrated: regress against h()-calibrated bins (True) or raw integer counts.
    """

    colour: str = "filter"
    delay: str = "mlp"
    order: int = 1
    domain: str = "log"
    calibrated: bool = True


class EventCrf(nn.Module):
    """Predicted event counts of each bin from the rendered log radiance at the b+1 poses.

    Args:
        spec: the model's choices.
        threshold: contrast threshold Theta (default: the sessions' ``DEFAULT_THRESHOLD``).
        cutoff_hz: photoreceptor cut-off f_c; tau = 1 / (2 pi f_c).
        hidden: width of the delay MLP.
        dead_time_s: a pixel's shortest interval between events; 0: no limit to its rate.
        polarity_scale: the ON and OFF thresholds over ``threshold`` (a step holds at most
            ``step / dead_time`` events, each of its polarity's threshold).
    """

    def __init__(
        self,
        spec: EventModelSpec,
        threshold: float = DEFAULT_THRESHOLD,
        cutoff_hz: float = 150.0,
        hidden: int = 128,
        dead_time_s: float = 0.0,
        polarity_scale: tuple[float, float] = (1.0, 1.0),
    ):
        super().__init__()
        self.spec = spec
        self.threshold = threshold
        self.dead_time_s = dead_time_s
        self.polarity_scale = polarity_scale
        self.tau_s = 1.0 / (2 * math.pi * cutoff_hz)
        self.delay = nn.Sequential(
            nn.Linear(1, hidden), nn.ReLU(), nn.Linear(hidden, 1), nn.Sigmoid()
        )
        self.mix_logits = nn.Parameter(torch.zeros(3))

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """Warm the delay MLP like the RGB CRF (towards clip(softplus(x), 0, 1))."""
        return warm_start_module(self.delay, steps, lr, seed, channels=1)

    def pixel_log_radiance(self, log_radiance: torch.Tensor, mix: torch.Tensor) -> torch.Tensor:
        """``(R, P)`` log radiance each event pixel sees (recorded filter or learned mix)."""
        if self.spec.colour == "learned":
            mix = torch.softmax(self.mix_logits, dim=0).expand(mix.shape[0], 3)
        return event_log_radiance(log_radiance, mix)

    def forward(
        self,
        log_radiance: torch.Tensor,
        mix: torch.Tensor,
        exposure_s: torch.Tensor,
        subframes: int = 1,
    ) -> torch.Tensor:
        """Predicted counts ``(R, b)``.

        Args:
            log_radiance: ``(R, b * subframes + 1, 3)``: every ``subframes``-th point is a latent
                one, the bins' ends.
            mix: ``(R, 3)`` colour weights of each pixel.
            exposure_s: ``(R,)`` exposure of the pixel's frame; a bin lasts exposure / b.
            subframes: points per bin. The pixel is followed from point to point (its low-pass,
                and with a dead time the events it owes), and each bin holds what its steps
                fired: an edge that crosses a pixel early in a bin is owed from then on, not
                spread over the bin.
        """
        pixel = self.pixel_log_radiance(log_radiance, mix)
        step_s = (exposure_s / max(pixel.shape[1] - 1, 1))[:, None]
        counts = predicted_counts(self.filtered(pixel, exposure_s, step_s), self.threshold)
        if self.dead_time_s > 0:
            most = step_s[:, 0] / self.dead_time_s
            counts = rate_limited(
                counts, most * self.polarity_scale[0], most * self.polarity_scale[1]
            )
        return counts.reshape(counts.shape[0], -1, subframes).sum(dim=2)

    def filtered(
        self, pixel: torch.Tensor, exposure_s: torch.Tensor, step_s: torch.Tensor
    ) -> torch.Tensor:
        """``(R, P)`` the pixel's log radiance after the delay low-pass (unchanged with none)."""
        if self.spec.delay == "none":
            return pixel
        factor = DELAY_FACTORS[self.spec.delay](self, pixel, exposure_s)
        epsilon = factor * step_s / self.tau_s
        if self.spec.domain == "linear":
            linear = torch.exp(pixel.clamp(-_LOG_LIMIT, _LOG_LIMIT))
            return torch.log(low_pass(linear, epsilon, self.spec.order).clamp(min=1e-30))
        return low_pass(pixel, epsilon, self.spec.order)


def _learned_factor(crf: EventCrf, pixel: torch.Tensor, exposure_s: torch.Tensor) -> torch.Tensor:
    return crf.delay(pixel[..., None]).squeeze(-1)


def _v2e_factor(crf: EventCrf, pixel: torch.Tensor, exposure_s: torch.Tensor) -> torch.Tensor:
    return v2e_intensity_factor(pixel + torch.log(exposure_s)[:, None])


DELAY_FACTORS = {"mlp": _learned_factor, "v2e": _v2e_factor}
"""Bandwidth factor f_ev in (0, 1] of each delay model (``none`` skips the low-pass)."""
