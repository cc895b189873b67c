"""The pixel-wise RGB response (eq. 7): three 1->128->1 MLPs on ln(radiance x s), sigmoid out."""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F  # noqa: N812
from torch import nn

from seenerf.errors import ConfigError

__all__ = [
    "LinearCrf",
    "MonotoneCrf",
    "PowerCrf",
    "RgbCrf",
    "TabulatedCrf",
    "anchor_error",
    "apply_power_crf",
    "apply_rgb_crf",
    "interpolate_response",
    "rising_output_weights",
    "warm_start_target",
]


def apply_rgb_crf(
    log_exposure: torch.Tensor,
    weight_in: torch.Tensor,
    bias_in: torch.Tensor,
    weight_out: torch.Tensor,
    bias_out: torch.Tensor,
) -> torch.Tensor:
    """LDR value of each channel from its own one-hidden-layer MLP.

    Args:
        log_exposure: ``(..., 3)`` ln(radiance) + ln(exposure seconds) per channel.
        weight_in: ``(3, K)`` first-layer weights.
        bias_in: ``(3, K)`` first-layer biases.
        weight_out: ``(3, K)`` second-layer weights.
        bias_out: ``(3,)`` second-layer biases.

    Returns:
        ``(..., 3)`` LDR values in (0, 1).
    """
    hidden = torch.relu(log_exposure[..., None] * weight_in + bias_in)
    return torch.sigmoid((hidden * weight_out).sum(-1) + bias_out)


def rising_output_weights(weight_in: torch.Tensor, weight_out: torch.Tensor) -> torch.Tensor:
    """Second-layer weights that make every hidden unit's term rise with exposure.

    A hidden unit ``relu(w_in x + b)`` rises where ``w_in > 0`` and falls where ``w_in < 0``;
    weighted by ``|w_out|`` with ``w_in``'s sign, each term rises, and so does their sum: a
    response never reads darker for more light. Unconstrained, the MLP can fold over above the
    exposures the frames show (one learned curve fell from 0.91 to 0 past its clip level, and the
    brightest views rendered black).
    """
    return weight_out.abs() * torch.sign(weight_in)


def apply_power_crf(log_exposure: torch.Tensor, exponent: torch.Tensor) -> torch.Tensor:
    """EvHDR-GS response ``min(x^a, 1)``, x = radiance x seconds, one exponent for all channels."""
    return torch.exp(exponent * log_exposure).clamp(max=1.0)


def apply_monotone_crf(
    log_exposure: torch.Tensor,
    slopes: torch.Tensor,
    offset: torch.Tensor,
    knots: tuple[float, float],
    anchor_log_exposure: float,
) -> torch.Tensor:
    """LDR value of each channel: ``sigmoid(offset + h(x) - h(anchor))``, ``h`` rising.

    ``h``'s slope goes linearly from ``slopes[:, 0]`` at the first knot to ``slopes[:, 1]`` at
    the second (both positive) and stays at each beyond its knot, so ``h`` is quadratic
    between the knots and straight outside.

    Args:
        log_exposure: ``(..., 3)`` ln(radiance x seconds) per channel.
        slopes: ``(3, 2)`` positive slopes of ``h`` at the two knots.
        offset: ``(3,)`` the pre-sigmoid value at the anchor.
        knots: the two knots' ln exposures, increasing.
        anchor_log_exposure: where ``h`` is zero.
    """
    low, high = knots
    width = high - low
    start, end = slopes[:, 0], slopes[:, 1]

    def rise(x: torch.Tensor) -> torch.Tensor:
        from_low = x - low
        inside = from_low.clamp(0.0, width)
        past = (from_low - width).clamp(min=0.0)
        return start * from_low + (end - start) * (inside.square() / (2 * width) + past)

    anchor = torch.full_like(offset, anchor_log_exposure)
    return torch.sigmoid(offset + rise(log_exposure) - rise(anchor))


def interpolate_response(
    log_exposure: torch.Tensor, table_x: torch.Tensor, table_values: torch.Tensor
) -> torch.Tensor:
    """Piecewise-linear response of each channel from a table, held constant beyond its ends.

    Args:
        log_exposure: ``(..., 3)`` ln(radiance x seconds) per channel.
        table_x: ``(K,)`` increasing sample positions.
        table_values: ``(K, 3)`` response of each channel at ``table_x``.
    """
    x = log_exposure.clamp(float(table_x[0]), float(table_x[-1]))
    upper = torch.searchsorted(table_x, x.detach().contiguous()).clamp(1, len(table_x) - 1)
    lower = upper - 1
    x0, x1 = table_x[lower], table_x[upper]
    channel = torch.arange(3, device=x.device).expand_as(upper)
    y0, y1 = table_values[lower, channel], table_values[upper, channel]
    t = (x - x0) / (x1 - x0).clamp(min=1e-12)
    return y0 + t * (y1 - y0)


def warm_start_target(x: torch.Tensor) -> torch.Tensor:
    """The reference warm-start curve ``clip(ln(1 + e^x), 0, 1)``."""
    return F.softplus(x).clamp(0.0, 1.0)


class RgbCrf(nn.Module):
    """Three per-channel response MLPs with the reference warm start and anchor term, rising.

    The reference leaves the MLPs free; here each is held rising
    (:func:`rising_output_weights`), as every camera's response is.

    Args:
        hidden: hidden width K (128).
        anchor_log_exposure: ln(radiance x seconds) of the anchor point (0: unit exposure).
        anchor_value: LDR value the anchor must map to (0.5).
        seed: initialisation seed.
    """

    clips_hard = False
    """Its curve flattens smoothly: a clipped frame still tells the field how far above it is."""

    def __init__(
        self,
        hidden: int = 128,
        anchor_log_exposure: float = 0.0,
        anchor_value: float = 0.5,
        seed: int = 0,
    ):
        super().__init__()
        generator = torch.Generator().manual_seed(seed)
        # PyTorch's default Linear initialisation: U(-1/sqrt(fan_in), 1/sqrt(fan_in)).
        self.weight_in = nn.Parameter(torch.rand(3, hidden, generator=generator) * 2 - 1)
        self.bias_in = nn.Parameter(torch.rand(3, hidden, generator=generator) * 2 - 1)
        bound = 1.0 / math.sqrt(hidden)
        self.weight_out = nn.Parameter((torch.rand(3, hidden, generator=generator) * 2 - 1) * bound)
        self.bias_out = nn.Parameter((torch.rand(3, generator=generator) * 2 - 1) * bound)
        self.anchor_log_exposure = anchor_log_exposure
        self.anchor_value = anchor_value

    def forward(self, log_exposure: torch.Tensor) -> torch.Tensor:
        """See :func:`apply_rgb_crf` and :func:`rising_output_weights`."""
        weight_out = rising_output_weights(self.weight_in, self.weight_out)
        return apply_rgb_crf(log_exposure, self.weight_in, self.bias_in, weight_out, self.bias_out)

    def anchor_loss(self) -> torch.Tensor:
        """See :func:`anchor_error`."""
        return anchor_error(self, self.weight_in)

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """Fit ``clip(softplus(x), 0, 1)`` on x ~ U[-3, 3] with its own Adam; return last loss."""
        return warm_start_module(self, steps, lr, seed, channels=3)


class MonotoneCrf(nn.Module):
    """A rising S-curve of three numbers per channel (:func:`apply_monotone_crf`).

    The alternative to :class:`RgbCrf`'s MLPs (``--response monotone``): it can only rise and
    bend smoothly. It starts as ``sigmoid(x - anchor)``, a slope of 1 everywhere, and needs no
    warm start. Frames of one exposure never linked by events hardly move it from there, so on
    them it acts as a prior on how many ln units the frames' values span.

    Args:
        anchor_log_exposure: ln(radiance x seconds) of the anchor point.
        anchor_value: LDR value the anchor must map to.
    """

    SPAN = 9.0
    """The knots lie this far below and above the anchor, in ln exposure (e^9: about 8,100)."""

    clips_hard = False

    def __init__(self, anchor_log_exposure: float = 0.0, anchor_value: float = 0.5):
        super().__init__()
        unit_slope = math.log(math.e - 1.0)  # softplus of it is 1
        self.raw_slopes = nn.Parameter(torch.full((3, 2), unit_slope))
        self.offset = nn.Parameter(torch.zeros(3))
        self.anchor_log_exposure = float(anchor_log_exposure)
        self.anchor_value = float(anchor_value)
        self.knots = (self.anchor_log_exposure - self.SPAN, self.anchor_log_exposure + self.SPAN)

    def forward(self, log_exposure: torch.Tensor) -> torch.Tensor:
        """See :func:`apply_monotone_crf`."""
        slopes = F.softplus(self.raw_slopes)
        return apply_monotone_crf(
            log_exposure, slopes, self.offset, self.knots, self.anchor_log_exposure
        )

    def anchor_loss(self) -> torch.Tensor:
        """See :func:`anchor_error`."""
        return anchor_error(self, self.offset)

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """It starts as a sigmoid already; nothing to warm up."""
        return 0.0


class PowerCrf(nn.Module):
    """Module form of :func:`apply_power_crf`; the exponent starts at 1/2.2."""

    clips_hard = False

    def __init__(self, anchor_log_exposure: float = 0.0, anchor_value: float = 0.5):
        super().__init__()
        self.exponent = nn.Parameter(torch.tensor(1 / 2.2))

    def forward(self, log_exposure: torch.Tensor) -> torch.Tensor:
        """See :func:`apply_power_crf`."""
        return apply_power_crf(log_exposure, self.exponent)

    def anchor_loss(self) -> torch.Tensor:
        """The power curve has no free offset to anchor; zero."""
        return self.exponent.new_zeros(())

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """Nothing to warm up."""
        return 0.0


class LinearCrf(nn.Module):
    """A raw frame's response: linear in exposure above a black level, clipped at saturation.

    Nothing to learn: the field's scale is the slope. ``black + (anchor_value - black) x`` with
    ``x`` the exposure over the anchor's, so the anchor maps to ``anchor_value`` as the learned
    curve's does; at most ``saturation`` (no gradient beyond, as a clipped pixel says only that
    it is at least that bright).

    Args:
        black: normalised value of no light; ``saturation`` where the pixel clips.
        anchor_log_exposure: ln(radiance x seconds) of the anchor point.
        anchor_value: LDR value at the anchor point.
    """

    clips_hard = True
    """No gradient above saturation: the light above the clip level is the events' alone."""

    def __init__(
        self,
        black: float,
        saturation: float,
        anchor_log_exposure: float = 0.0,
        anchor_value: float = 0.5,
    ):
        super().__init__()
        if not self.fits(black, saturation, anchor_value):
            raise ConfigError(
                f"the measured black level {black:.3f} is not below the anchor value "
                f"{anchor_value} and the clip level {saturation:.3f}; fit with --response learned"
            )
        self.black, self.saturation = float(black), float(saturation)
        self.anchor_log_exposure = float(anchor_log_exposure)
        self.slope = float(anchor_value) - self.black

    @staticmethod
    def fits(black: float, saturation: float, anchor_value: float = 0.5) -> bool:
        """True when a line from ``black`` through the anchor, clipped at ``saturation``, can be."""
        return 0.0 <= black < min(anchor_value, saturation)

    def forward(self, log_exposure: torch.Tensor) -> torch.Tensor:
        """LDR value of each channel from ln(radiance x seconds)."""
        linear = self.black + self.slope * torch.exp(log_exposure - self.anchor_log_exposure)
        return linear.clamp(max=self.saturation)

    def anchor_loss(self) -> torch.Tensor:
        """The anchor holds by construction; zero."""
        return torch.zeros(())

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """Nothing to warm up."""
        return 0.0


class TabulatedCrf(nn.Module):
    """A known response (the emulator's truth), nothing to learn: the oracle's LDR views.

    Args:
        log_exposure: ``(K,)`` increasing ln(radiance x seconds) samples.
        values: ``(K, 3)`` response at those samples.
    """

    def __init__(self, log_exposure, values):
        super().__init__()
        self.register_buffer(
            "table_x", torch.as_tensor(log_exposure, dtype=torch.float32), persistent=False
        )
        self.register_buffer(
            "table_values", torch.as_tensor(values, dtype=torch.float32), persistent=False
        )
        top = self.table_values.amax(dim=0)
        # A raw sensor's table reaches its clip level and stays there; a film-like one only
        # approaches its top at the table's end.
        self.clips_hard = bool((self.table_values[:-1] >= top - 1e-6).any())

    def forward(self, log_exposure: torch.Tensor) -> torch.Tensor:
        """See :func:`interpolate_response`."""
        return interpolate_response(log_exposure, self.table_x, self.table_values)

    def anchor_loss(self) -> torch.Tensor:
        """A known response needs no anchor; zero."""
        return self.table_x.new_zeros(())

    def warm_start(self, steps: int = 500, lr: float = 5e-4, seed: int = 0) -> float:
        """Nothing to warm up."""
        return 0.0


def anchor_error(crf: nn.Module, like: torch.Tensor) -> torch.Tensor:
    """A learned response's squared error at its anchor, mean over the three channels.

    ``like``: one of its parameters, whose device and precision the anchor point takes.
    """
    point = like.new_full((3,), crf.anchor_log_exposure)
    return (crf(point) - crf.anchor_value).square().mean()


def warm_start_module(module: nn.Module, steps: int, lr: float, seed: int, channels: int) -> float:
    """Adam on ``module`` alone towards :func:`warm_start_target`; mean L2 norm of the error."""
    generator = torch.Generator().manual_seed(seed)
    optimizer = torch.optim.Adam(module.parameters(), lr=lr)
    loss = torch.zeros(())
    for _ in range(steps):
        x = torch.rand(1024, channels, generator=generator) * 6.0 - 3.0
        loss = (module(x) - warm_start_target(x)).norm(dim=-1).mean()
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    return float(loss.detach())
