"""Field, sampler and volume rendering composed: rays in, per-ray rendered values out."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import torch
from torch import nn

from seenerf.fields import FIELDS
from seenerf.render.frustum import FrustumSpace
from seenerf.render.rays import SceneBox, intersect_box
from seenerf.render.sampler_spec import SamplerSpec
from seenerf.render.sampling import (
    OccupancyGrid,
    PackedSamples,
    importance_samples,
    stratified_samples,
)
from seenerf.render.volume import composite, sample_weights

__all__ = ["WEIGHT_CUTOFF", "RadianceRenderer", "RenderedRays", "ValueFn"]

WEIGHT_CUTOFF = 1e-4
"""Samples whose blending weight is below this get no radiance query (their share is dropped)."""

ValueFn = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
"""Maps per-sample log radiance ``(S, 3)`` and ray index ``(S,)`` to the values to composite."""


@dataclass
class RenderedRays:
    """Output of one rendering pass (one per field in a hierarchical sampler)."""

    values: torch.Tensor
    opacity: torch.Tensor
    depth: torch.Tensor
    num_samples: int
    sample_weights: torch.Tensor | None = None


class RadianceRenderer(nn.Module):
    """Renders rays through one field (occupancy) or a coarse and a fine field (hierarchical).

    Args:
        field_name: key of :data:`seenerf.fields.FIELDS`.
        field_args: keyword arguments of the field class.
        sampler: the sampler specification.
        box: the scene box, in world units or, with ``space``, in NDC.
        space: the NDC of a forward-facing scene (rays are mapped into it first, and run from
            the near plane to infinity), or None for world coordinates.
    """

    def __init__(
        self,
        field_name: str,
        field_args: dict,
        sampler: SamplerSpec,
        box: SceneBox,
        space: FrustumSpace | None = None,
    ):
        super().__init__()
        self.sampler = sampler
        self.box = box
        self.space = space
        fields = [FIELDS[field_name](**field_args)]
        if sampler.kind == "hierarchical":
            fields.append(FIELDS[field_name](**field_args))
        self.fields = nn.ModuleList(fields)
        self.background = nn.Parameter(torch.zeros(3))
        self.grid = OccupancyGrid(sampler.grid_resolution) if sampler.kind == "occupancy" else None

    def density(self, points: torch.Tensor) -> torch.Tensor:
        """Density of the last (fine) field at box points, for the occupancy grid."""
        return self.fields[-1].density(points)

    def forward(
        self,
        origins: torch.Tensor,
        directions: torch.Tensor,
        near: float,
        far: float,
        value_fn: ValueFn | None = None,
        generator: torch.Generator | None = None,
    ) -> list[RenderedRays]:
        """Render ``(R, 3)`` world rays; ``generator`` set means training (jitter, density noise).

        ``near`` and ``far`` bound the ray parameter in world depth; in NDC the rays run from
        the space's near plane to infinity instead.
        """
        if self.space is not None:
            origins, directions = self.space.rays(origins, directions)
            near, far = 0.0, 1.0
        t_entry, t_exit = intersect_box(origins, directions, self.box, near, far)
        to_box = self._to_box(origins, directions)
        coarse, fine = self.sampler.counts(training=generator is not None)
        if self.grid is not None and fine > 0:
            samples = self._propose(
                t_entry, t_exit, origins, directions, to_box, generator, coarse, fine
            )
            return [self._shade_skipping(samples, origins, directions, value_fn, generator)]
        if self.grid is not None:
            samples = self.grid.sample(t_entry, t_exit, coarse, to_box, generator)
            return [self._shade_skipping(samples, origins, directions, value_fn, generator)]
        t, delta = stratified_samples(t_entry, t_exit, coarse, generator)
        coarse_pass = self._shade(
            self.fields[0],
            PackedSamples.from_dense(t, delta),
            origins,
            directions,
            value_fn,
            generator,
            keep_weights=True,
        )
        weights = coarse_pass.sample_weights.reshape(t.shape).detach()
        t, delta = importance_samples(t, delta, weights, fine, generator)
        fine_pass = self._shade(
            self.fields[1],
            PackedSamples.from_dense(t, delta),
            origins,
            directions,
            value_fn,
            generator,
        )
        return [coarse_pass, fine_pass]

    def _to_box(self, origins: torch.Tensor, directions: torch.Tensor):
        """``t (R, N) -> (R, N, 3)`` box coordinates, the box's affine map folded into each ray."""
        box_origins, box_directions = self._box_rays(origins, directions)

        def to_box(t: torch.Tensor) -> torch.Tensor:
            return torch.addcmul(box_origins[:, None], t[..., None], box_directions[:, None])

        return to_box

    def _box_rays(self, origins: torch.Tensor, directions: torch.Tensor):
        """Origins in box coordinates and directions scaled to box units per ray parameter."""
        scale = 2.0 / (origins.new_tensor(self.box.high) - origins.new_tensor(self.box.low))
        return self.box.normalise(origins), directions * scale

    def _points(self, samples: PackedSamples, origins, directions):
        index = samples.ray_index
        box_origins, box_directions = self._box_rays(origins, directions)
        points = torch.addcmul(box_origins[index], samples.t[:, None], box_directions[index])
        unit = directions / directions.norm(dim=-1, keepdim=True)
        box_delta = samples.delta * directions.norm(dim=-1)[index] * 2.0 / self.box.size
        return points, unit[index], box_delta

    def _noisy(self, density: torch.Tensor, generator) -> torch.Tensor:
        if generator is None or self.sampler.density_noise <= 0:
            return density
        noise = torch.randn(density.shape, generator=generator) * self.sampler.density_noise
        return torch.relu(density + noise.to(density.device))

    def _finish(
        self,
        weights,
        opacity,
        log_radiance,
        index,
        samples_t,
        rays: int,
        value_fn,
        num_samples: int,
        kept_weights=None,
    ) -> RenderedRays:
        ray_ids = torch.arange(rays, device=weights.device)
        if value_fn is None:
            values, background = log_radiance, self.background
        else:
            values = value_fn(log_radiance, index)
            background = value_fn(self.background.expand(rays, 3), ray_ids)
        rendered = composite(weights, values, index, opacity, background)
        depth = torch.zeros_like(opacity).index_add_(0, index, weights * samples_t)
        return RenderedRays(rendered, opacity, depth, num_samples, kept_weights)

    def _shade(
        self,
        field,
        samples: PackedSamples,
        origins,
        directions,
        value_fn,
        generator,
        keep_weights: bool = False,
    ) -> RenderedRays:
        points, unit, box_delta = self._points(samples, origins, directions)
        density, log_radiance = field(points, unit)
        density = self._noisy(density, generator)
        weights, opacity = sample_weights(
            density, box_delta, samples.ray_index, len(origins), samples.per_ray
        )
        return self._finish(
            weights,
            opacity,
            log_radiance,
            samples.ray_index,
            samples.t,
            len(origins),
            value_fn,
            int(samples.t.numel()),
            weights if keep_weights else None,
        )

    @torch.no_grad()
    def _propose(
        self, t_entry, t_exit, origins, directions, to_box, generator, coarse: int, fine: int
    ) -> PackedSamples:
        """Densities at ``coarse`` occupied candidates (no gradients), then ``fine`` samples."""
        t, delta = stratified_samples(t_entry, t_exit, coarse, generator)
        points = to_box(t).reshape(-1, 3)
        keep = self.grid.lookup(points) & (delta.reshape(-1) > 0)
        density = torch.zeros(t.numel(), device=t.device)
        density[keep] = self.fields[0].density(points[keep])
        box_delta = delta * directions.norm(dim=-1, keepdim=True) * 2.0 / self.box.size
        packed = PackedSamples.from_dense(t, box_delta)
        weights, _ = sample_weights(
            density, packed.delta, packed.ray_index, len(origins), packed.per_ray
        )
        fine_t, fine_delta = importance_samples(
            t, delta, weights.reshape(t.shape), fine, generator, merge=False
        )
        return PackedSamples.from_dense(fine_t, fine_delta)

    def _shade_skipping(
        self, samples: PackedSamples, origins, directions, value_fn, generator
    ) -> RenderedRays:
        """Density everywhere sampled, radiance only where the blending weight matters."""
        field = self.fields[0]
        points, unit, box_delta = self._points(samples, origins, directions)
        density = self._noisy(field.density(points), generator)
        weights, _ = sample_weights(
            density, box_delta, samples.ray_index, len(origins), samples.per_ray
        )
        keep = weights.detach() > WEIGHT_CUTOFF
        index = samples.ray_index[keep]
        kept = weights[keep]
        opacity = torch.zeros(len(origins), device=kept.device).index_add_(0, index, kept)
        log_radiance = field.radiance(points[keep], unit[keep])
        return self._finish(
            kept,
            opacity,
            log_radiance,
            index,
            samples.t[keep],
            len(origins),
            value_fn,
            int(samples.t.numel()),
        )
