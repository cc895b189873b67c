"""See-NeRF composed from named parts: radiance renderer, exposure integral, RGB CRF, event CRF."""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn

from seenerf.model.variants import Variant
from seenerf.render.renderer import RadianceRenderer
from seenerf.sensors.event_crf import EventCrf, EventModelSpec
from seenerf.sensors.exposure import blur_log_radiance
from seenerf.sensors.rgb_crf import PowerCrf, RgbCrf, TabulatedCrf, interpolate_response

__all__ = ["CRFS", "IMAGING", "RESPONSE_TABLE_SIZE", "Prediction", "RayBatch", "SeeNerfModel"]

CRFS = {"mlp": RgbCrf, "power": PowerCrf, "true": TabulatedCrf}
"""RGB response models by name (``none`` means no response model; ``true`` is a known table)."""

RESPONSE_TABLE_SIZE = 16_384
"""Samples of the learned response tabulated for whole images (:meth:`SeeNerfModel.ldr_images`)."""


@dataclass
class RayBatch:
    """Pixels of training frames, each seen from its frame's b+1 latent poses (and sub-frames).

    Attributes:
        origins: ``(R, P, 3)`` ray origins per pixel and pose, P = b m + 1 with m sub-frames
            per bin; ``directions`` likewise.
        weights: ``(R, P)`` exposure-integral weights.
        exposure_s: ``(R,)`` exposure time of the pixel's frame.
        mix: ``(R, 3)`` colour weights of the pixel; ``channel`` ``(R,)`` its response channel.
        ldr: ``(R,)`` recorded value in [0, 1]; ``bins`` ``(R, b)`` event counts.
        subframes: m; every m-th pose is a latent pose, where the event model looks.
    """

    origins: torch.Tensor
    directions: torch.Tensor
    weights: torch.Tensor
    exposure_s: torch.Tensor
    mix: torch.Tensor
    channel: torch.Tensor
    ldr: torch.Tensor
    bins: torch.Tensor
    subframes: int = 1


@dataclass
class Prediction:
    """One rendering pass's prediction for a :class:`RayBatch`."""

    ldr: torch.Tensor
    counts: torch.Tensor | None
    log_radiance: torch.Tensor
    num_samples: int


def pixel_imaging(crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor):
    """The paper: blur in linear HDR (eq. 6), the pixel's colour filter, then its CRF (eq. 7).

    Returns:
        ``(R,)`` LDR values and the ``(R, P, 3)`` log radiance at the latent poses.
    """
    blurred = blur_log_radiance(values, batch.weights)
    pixel_log = torch.logsumexp(blurred + torch.log(batch.mix.clamp(min=1e-12)), dim=-1)
    ldr3 = crf((pixel_log + log_dt)[:, None].expand(-1, 3))
    return ldr3.gather(1, batch.channel[:, None]).squeeze(1), values


def point_imaging(crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor):
    """HDR-NeRF style: per-sample CRF already composited (first 3 channels), blur in LDR."""
    blurred = (batch.weights[..., None] * values[..., :3]).sum(dim=1)
    return (blurred * batch.mix).sum(dim=-1), values[..., 3:]


def ldr_field_imaging(crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor):
    """Naive LDR field: sigmoid of the rendered value is LDR, blur in LDR, no response model."""
    blurred = (batch.weights[..., None] * torch.sigmoid(values)).sum(dim=1)
    return (blurred * batch.mix).sum(dim=-1), values


IMAGING = {"pixel": pixel_imaging, "point": point_imaging, "ldr-field": ldr_field_imaging}
"""How rendered values at the b+1 poses become one blurry LDR pixel, by variant imaging name."""


class SeeNerfModel(nn.Module):
    """The whole imaging model of a variant.

    Args:
        renderer: field + sampler + volume rendering.
        variant: which parts are used.
        event_spec: the event model (the variant's, possibly with another low-pass reading).
        near: near depth; ``far`` far depth.
        reference_exposure_s: exposure of the training frames (for the LDR-field variant).
        crf_args: keyword arguments of the RGB CRF; ``event_args`` of the event CRF.
    """

    def __init__(
        self,
        renderer: RadianceRenderer,
        variant: Variant,
        event_spec: EventModelSpec | None,
        near: float,
        far: float,
        reference_exposure_s: float,
        crf_args: dict,
        event_args: dict,
    ):
        super().__init__()
        self.renderer = renderer
        self.variant = variant
        self.near, self.far = near, far
        self.reference_exposure_s = reference_exposure_s
        self.crf = CRFS[variant.crf](**crf_args) if variant.crf in CRFS else None
        self.event_crf = EventCrf(event_spec, **event_args) if event_spec is not None else None

    def warm_start(self, steps: int, seed: int) -> None:
        """Reference warm start of the response MLPs (before any training step)."""
        if self.crf is not None:
            self.crf.warm_start(steps, seed=seed)
        if self.event_crf is not None:
            self.event_crf.warm_start(steps, seed=seed + 1)

    def forward(
        self, batch: RayBatch, generator: torch.Generator | None = None
    ) -> list[Prediction]:
        """Predicted blurry LDR values and event counts, one :class:`Prediction` per pass."""
        rays, poses = batch.weights.shape
        log_dt = torch.log(batch.exposure_s)
        value_fn = None
        if self.variant.imaging == "point":
            log_dt_rays = log_dt.repeat_interleave(poses)

            def value_fn(log_radiance, index):
                ldr = self.crf(log_radiance + log_dt_rays[index, None])
                return torch.cat([ldr, log_radiance], dim=-1)

        passes = self.renderer(
            batch.origins.reshape(-1, 3),
            batch.directions.reshape(-1, 3),
            self.near,
            self.far,
            value_fn,
            generator,
        )
        return [
            self._predict(
                batch, rendered.values.reshape(rays, poses, -1), log_dt, rendered.num_samples
            )
            for rendered in passes
        ]

    def _predict(
        self, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor, num_samples: int
    ) -> Prediction:
        ldr, log_radiance = IMAGING[self.variant.imaging](self.crf, batch, values, log_dt)
        counts = None
        if self.event_crf is not None:
            latent = log_radiance[:, :: batch.subframes]
            counts = self.event_crf(latent, batch.mix, batch.exposure_s)
        return Prediction(ldr, counts, log_radiance, num_samples)

    def render_log_radiance(self, origins: torch.Tensor, directions: torch.Tensor) -> torch.Tensor:
        """``(R, 3)`` rendered log radiance of sharp rays (last pass), no jitter."""
        return self.renderer(origins, directions, self.near, self.far)[-1].values

    def hdr_from_log(self, log_radiance: torch.Tensor) -> torch.Tensor:
        """Linear HDR radiance ``(R, 3)``; the LDR-field variant's output is its LDR image."""
        if self.variant.imaging == "ldr-field":
            return torch.sigmoid(log_radiance)
        return torch.exp(log_radiance.clamp(max=60.0))

    def ldr_from_log(self, log_radiance: torch.Tensor, exposure_s: float) -> torch.Tensor:
        """LDR ``(R, 3)`` at a new exposure through the learned per-pixel response.

        The 3-D point CRF is applied here after rendering (an approximation for that variant);
        the LDR field scales its output by the exposure ratio and clips.
        """
        if self.variant.imaging == "ldr-field" or self.crf is None:
            ratio = exposure_s / self.reference_exposure_s
            return (torch.sigmoid(log_radiance) * ratio).clamp(0.0, 1.0)
        return self.crf(log_radiance + math.log(exposure_s))

    def ldr_images(self, log_radiance: torch.Tensor, exposures_s) -> list[torch.Tensor]:
        """:meth:`ldr_from_log` at each exposure, for whole images.

        The learned response is a function of one value per channel, so it is evaluated once
        on a grid of :data:`RESPONSE_TABLE_SIZE` points spanning every value the images need
        and interpolated: a 346x260 view at five exposures asks the MLPs for 16,384 values per
        channel instead of 450,000 (the interpolation error stays below 1e-3, a quarter of an
        8-bit level).
        """
        if self.variant.imaging == "ldr-field" or not isinstance(self.crf, RgbCrf):
            return [self.ldr_from_log(log_radiance, exposure) for exposure in exposures_s]
        shifts = [math.log(exposure) for exposure in exposures_s]
        low = float(log_radiance.min()) + min(shifts)
        high = float(log_radiance.max()) + max(shifts)
        grid = torch.linspace(low, high, RESPONSE_TABLE_SIZE, device=log_radiance.device)
        table = self.crf(grid[:, None].expand(-1, 3))
        return [interpolate_response(log_radiance + shift, grid, table) for shift in shifts]
