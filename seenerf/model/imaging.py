"""How rendered values become pixels: blurry LDR training pixels, and HDR and LDR images.

A variant's imaging is one of three objects. :class:`Imaging` is the paper's: blur in linear
HDR, then the pixel's response. :class:`PointImaging` applies the response to every 3-D sample
and blurs in LDR (HDR-NeRF style); :class:`LdrFieldImaging` has the field render LDR directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from seenerf.render.renderer import ValueFn
from seenerf.sensors.exposure import blur_log_radiance
from seenerf.sensors.rgb_crf import RgbCrf, interpolate_response

__all__ = [
    "LDR_FIELD",
    "PIXEL",
    "POINT",
    "RESPONSE_TABLE_SIZE",
    "Imaging",
    "LdrFieldImaging",
    "PointImaging",
    "RayBatch",
    "SpanBatch",
]

RESPONSE_TABLE_SIZE = 16_384
"""Samples of the learned response tabulated for whole images (:meth:`Imaging.ldr_images`)."""


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
        settled: ``(R, b+1)`` bool, where the pixel had fired all it owed at a latent pose (the
            event loss compares counts between such poses).
        subframes: m; every m-th pose is a latent pose, where the event model looks.
        lone: ``(R,)`` bool, the pixels whose events are compared over their whole exposure
            as well (of frames alone in their stretch of the stream); None: no pixel's.
    """

    origins: torch.Tensor
    directions: torch.Tensor
    weights: torch.Tensor
    exposure_s: torch.Tensor
    mix: torch.Tensor
    channel: torch.Tensor
    ldr: torch.Tensor
    bins: torch.Tensor
    settled: torch.Tensor
    subframes: int = 1
    lone: torch.Tensor | None = None


@dataclass
class SpanBatch:
    """Pixels seen at two latent points of one stretch of the stream, and the change between.

    Attributes:
        origins: ``(R, 2, 3)`` ray origins at the span's first and last point; ``directions``
            likewise.
        mix: ``(R, 3)`` colour weights of each pixel.
        change: ``(R,)`` the recorded ln change from the first point to the last, in units of
            the mean threshold.
        known: ``(R,)`` bool, the change is whole: both points in one stretch, the pixel settled
            at each.
        ldr: ``(R, 2)`` the pixel's recorded value in the first point's frame and the last's.
    """

    origins: torch.Tensor
    directions: torch.Tensor
    mix: torch.Tensor
    change: torch.Tensor
    known: torch.Tensor
    ldr: torch.Tensor


def _scaled_ldr(
    log_radiance: torch.Tensor, exposure_s: float, reference_exposure_s: float
) -> torch.Tensor:
    """Sigmoid of the rendered value scaled by the exposure ratio and clipped: no response."""
    ratio = exposure_s / reference_exposure_s
    return (torch.sigmoid(log_radiance) * ratio).clamp(0.0, 1.0)


@dataclass(frozen=True)
class Imaging:
    """The paper: blur in linear HDR (eq. 6), the pixel's colour filter, then its CRF (eq. 7)."""

    def sample_values(self, crf, log_dt: torch.Tensor, poses: int) -> ValueFn | None:
        """What the renderer composites per sample (None: the log radiance itself).

        Args:
            crf: the RGB response, or None.
            log_dt: ``(R,)`` log exposure time of each pixel.
            poses: poses per pixel; the renderer's rays are pixel after pixel, pose after pose.
        """
        return None

    def blurry_ldr(
        self, crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """``(R,)`` blurry LDR pixels and the ``(R, P, 3)`` log radiance at the poses.

        Args:
            crf: the RGB response, or None.
            batch: the pixels.
            values: ``(R, P, C)`` composited values per pixel and pose.
            log_dt: ``(R,)`` log exposure time of each pixel.
        """
        blurred = blur_log_radiance(values, batch.weights)
        pixel_log = torch.logsumexp(blurred + torch.log(batch.mix.clamp(min=1e-12)), dim=-1)
        ldr3 = crf((pixel_log + log_dt)[:, None].expand(-1, 3))
        return ldr3.gather(1, batch.channel[:, None]).squeeze(1), values

    def hdr(self, log_radiance: torch.Tensor) -> torch.Tensor:
        """Linear HDR radiance ``(R, 3)`` of rendered log radiance."""
        return torch.exp(log_radiance.clamp(max=60.0))

    def ldr(
        self, crf, log_radiance: torch.Tensor, exposure_s: float, reference_exposure_s: float
    ) -> torch.Tensor:
        """LDR ``(R, 3)`` at a new exposure through the response (scaled and clipped without)."""
        if crf is None:
            return _scaled_ldr(log_radiance, exposure_s, reference_exposure_s)
        return crf(log_radiance + math.log(exposure_s))

    def tabulates(self, crf) -> bool:
        """Whether :meth:`ldr_images` reads the response from a table: a learned MLP response."""
        return isinstance(crf, RgbCrf)

    def ldr_images(
        self, crf, log_radiance: torch.Tensor, exposures_s, reference_exposure_s: float
    ) -> list[torch.Tensor]:
        """:meth:`ldr` at each exposure, for whole images.

        The learned response is a function of one value per channel, so it is evaluated once
        on a grid of :data:`RESPONSE_TABLE_SIZE` points spanning every value the images need
        and interpolated: a 346x260 view at five exposures asks the MLPs for 16,384 values per
        channel instead of 450,000 (the interpolation error stays below 1e-3, a quarter of an
        8-bit level).
        """
        if not self.tabulates(crf):
            return [
                self.ldr(crf, log_radiance, exposure, reference_exposure_s)
                for exposure in exposures_s
            ]
        shifts = [math.log(exposure) for exposure in exposures_s]
        low = float(log_radiance.min()) + min(shifts)
        high = float(log_radiance.max()) + max(shifts)
        grid = torch.linspace(low, high, RESPONSE_TABLE_SIZE, device=log_radiance.device)
        table = crf(grid[:, None].expand(-1, 3))
        return [interpolate_response(log_radiance + shift, grid, table) for shift in shifts]


@dataclass(frozen=True)
class PointImaging(Imaging):
    """HDR-NeRF style: the CRF on every 3-D sample, composited, then blurred in LDR.

    Views at a new exposure apply the response after rendering (an approximation).
    """

    def sample_values(self, crf, log_dt: torch.Tensor, poses: int) -> ValueFn:
        """Per sample: its LDR at its pixel's exposure, then its log radiance."""
        log_dt_rays = log_dt.repeat_interleave(poses)

        def value_fn(log_radiance: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
            ldr = crf(log_radiance + log_dt_rays[index, None])
            return torch.cat([ldr, log_radiance], dim=-1)

        return value_fn

    def blurry_ldr(
        self, crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """The composited LDR (first 3 channels) blurred and mixed; log radiance after them."""
        blurred = (batch.weights[..., None] * values[..., :3]).sum(dim=1)
        return (blurred * batch.mix).sum(dim=-1), values[..., 3:]


@dataclass(frozen=True)
class LdrFieldImaging(Imaging):
    """Naive LDR field: the sigmoid of the rendered value is LDR, blurred in LDR, no response.

    Its HDR output is its LDR image; a new exposure scales it by the exposure ratio and clips.
    """

    def blurry_ldr(
        self, crf, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """The sigmoid of the rendered values blurred and mixed."""
        blurred = (batch.weights[..., None] * torch.sigmoid(values)).sum(dim=1)
        return (blurred * batch.mix).sum(dim=-1), values

    def hdr(self, log_radiance: torch.Tensor) -> torch.Tensor:
        """The field's LDR image."""
        return torch.sigmoid(log_radiance)

    def ldr(
        self, crf, log_radiance: torch.Tensor, exposure_s: float, reference_exposure_s: float
    ) -> torch.Tensor:
        """The LDR image scaled by the exposure ratio and clipped (no response model)."""
        return _scaled_ldr(log_radiance, exposure_s, reference_exposure_s)

    def tabulates(self, crf) -> bool:
        """Never: there is no response to tabulate."""
        return False


PIXEL = Imaging()
POINT = PointImaging()
LDR_FIELD = LdrFieldImaging()
