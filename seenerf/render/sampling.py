"""Where along each ray the field is queried: stratified, importance, occupancy-skipping."""

from __future__ import annotations

from dataclasses import dataclass

import torch

__all__ = ["OccupancyGrid", "PackedSamples", "importance_samples", "stratified_samples"]


@dataclass
class PackedSamples:
    """Samples of many rays in one flat list, ray after ray.

    Attributes:
        ray_index: ``(S,)`` int64 ray of each sample, non-decreasing.
        t: ``(S,)`` ray parameter (depth) of each sample.
        delta: ``(S,)`` interval length represented by each sample, in ray-parameter units.
        per_ray: samples of every ray when all rays have the same count, 0 when ragged.
    """

    ray_index: torch.Tensor
    t: torch.Tensor
    delta: torch.Tensor
    per_ray: int = 0

    @staticmethod
    def from_dense(t: torch.Tensor, delta: torch.Tensor) -> PackedSamples:
        """Pack ``(R, N)`` samples, N per ray."""
        rays, count = t.shape
        index = torch.arange(rays, device=t.device).repeat_interleave(count)
        return PackedSamples(index, t.reshape(-1), delta.reshape(-1), count)


def stratified_samples(
    t_entry: torch.Tensor, t_exit: torch.Tensor, count: int, generator: torch.Generator | None
) -> tuple[torch.Tensor, torch.Tensor]:
    """``count`` samples per ray, one uniform in each of equal strata (centres without generator).

    Returns:
        ``t`` and ``delta``, each ``(R, count)``; an empty interval gives zero deltas.
    """
    fractions = torch.arange(count, dtype=t_entry.dtype, device=t_entry.device)
    jitter = (
        torch.rand(t_entry.shape[0], count, generator=generator, device=t_entry.device)
        if generator is not None
        else torch.full((t_entry.shape[0], count), 0.5, device=t_entry.device)
    )
    length = (t_exit - t_entry)[:, None]
    t = t_entry[:, None] + (fractions + jitter) / count * length
    return t, (length / count).expand_as(t).contiguous()


def importance_samples(
    t: torch.Tensor,
    delta: torch.Tensor,
    weights: torch.Tensor,
    count: int,
    generator: torch.Generator | None,
    merge: bool = True,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Inverse-CDF samples from coarse weights, sorted (and merged with the coarse samples).

    Args:
        t: ``(R, N)`` coarse sample centres.
        delta: ``(R, N)`` their interval lengths.
        weights: ``(R, N)`` coarse blending weights (detached).
        count: new samples per ray.
        generator: random source (None: evenly spaced quantiles).
        merge: return the coarse samples too (the reference's fine pass) or only the new ones.

    Returns:
        ``t`` and ``delta`` (distance to the next sample, the last to the interval's end) of the
        ``N + count`` (or ``count``) samples.
    """
    edges = torch.cat([t - delta / 2, (t[:, -1:] + delta[:, -1:] / 2)], dim=-1)
    pdf = weights + 1e-5
    pdf = pdf / pdf.sum(dim=-1, keepdim=True)
    cdf = torch.cat([torch.zeros_like(pdf[:, :1]), torch.cumsum(pdf, dim=-1)], dim=-1)
    if generator is None:
        uniform = torch.linspace(0.0, 1.0, count, device=t.device).expand(t.shape[0], count)
    else:
        uniform = torch.rand(t.shape[0], count, generator=generator, device=t.device)
    upper = torch.searchsorted(cdf, uniform.contiguous(), right=True).clamp(1, cdf.shape[-1] - 1)
    cdf_low, cdf_high = cdf.gather(1, upper - 1), cdf.gather(1, upper)
    edge_low, edge_high = edges.gather(1, upper - 1), edges.gather(1, upper)
    span = torch.where(cdf_high - cdf_low < 1e-5, torch.ones_like(cdf_low), cdf_high - cdf_low)
    fine = edge_low + (uniform - cdf_low) / span * (edge_high - edge_low)
    merged, _ = torch.sort(
        torch.cat([t, fine.detach()], dim=-1) if merge else fine.detach(), dim=-1
    )
    end = edges[:, -1:]
    merged_delta = torch.diff(torch.cat([merged, end], dim=-1), dim=-1).clamp(min=0.0)
    return merged, merged_delta


class OccupancyGrid:
    """A coarse boolean grid over the box marking cells that may hold matter (empty-space skipping).

    Args:
        resolution: cells per side.
        threshold: a cell is occupied when its density x cell size exceeds this optical depth.
    """

    def __init__(self, resolution: int = 64, threshold: float = 0.01):
        self.resolution = resolution
        self.threshold = threshold
        self.density = torch.full((resolution,) * 3, float("inf"))
        self.occupied = torch.ones((resolution,) * 3, dtype=torch.bool)
        self.visible = torch.ones((resolution,) * 3, dtype=torch.bool)

    def restrict_to_views(self, in_view) -> float:
        """Mark cells no training camera sees as empty for good; return the visible fraction.

        Args:
            in_view: ``(P, 3)`` box points -> ``(P,)`` bool, True where some camera sees them.
        """
        centres = self.centres()
        self.visible = in_view(centres).reshape(self.visible.shape)
        self.occupied &= self.visible
        return float(self.visible.float().mean())

    def centres(self, generator: torch.Generator | None = None) -> torch.Tensor:
        """``(G^3, 3)`` cell centres in box coordinates (jittered in the cell with a generator)."""
        axis = torch.arange(self.resolution, dtype=torch.float32)
        cells = torch.stack(torch.meshgrid(axis, axis, axis, indexing="ij"), dim=-1).reshape(-1, 3)
        offset = torch.rand(cells.shape, generator=generator) if generator is not None else 0.5
        return (cells + offset) / self.resolution * 2.0 - 1.0

    @torch.no_grad()
    def update(self, density_fn, generator: torch.Generator | None = None, decay: float = 0.95):
        """Refresh from ``density_fn(points (P, 3)) -> (P,)`` density per box unit."""
        points = self.centres(generator)
        density = torch.cat([density_fn(chunk) for chunk in points.split(32768)]).cpu()
        density = density.reshape(self.density.shape)
        previous = torch.where(torch.isinf(self.density), density, self.density * decay)
        self.set_density(torch.maximum(previous, density))
        return float(self.occupied.float().mean())

    def set_density(self, density: torch.Tensor) -> None:
        """Take ``density`` (a refresh's, or a checkpoint's) and mark the occupied cells."""
        self.density = density
        cell = 2.0 / self.resolution
        self.occupied = (density * cell > self.threshold) & self.visible

    def lookup(self, points: torch.Tensor) -> torch.Tensor:
        """Occupancy ``(P,)`` bool of box points; points outside the box are empty."""
        side = self.resolution
        index = ((points + 1.0) * (0.5 * side)).floor().long()
        inside = ((index >= 0) & (index < side)).all(dim=-1)
        index = index.clamp_(0, side - 1)
        flat = (index[:, 0] * side + index[:, 1]) * side + index[:, 2]
        occupied = self.occupied.to(points.device).reshape(-1).take(flat)
        return occupied & inside

    def sample(
        self,
        t_entry: torch.Tensor,
        t_exit: torch.Tensor,
        count: int,
        to_box,
        generator: torch.Generator | None,
    ) -> PackedSamples:
        """Stratified ``count`` candidates per ray, keeping only those in occupied cells.

        Args:
            t_entry: ``(R,)`` entry parameters.
            t_exit: ``(R,)`` exit parameters.
            count: candidates per ray.
            to_box: ``(R, N) -> (R, N, 3)`` box coordinates of ray parameters.
            generator: random source (None: stratum centres).
        """
        t, delta = stratified_samples(t_entry, t_exit, count, generator)
        keep = self.lookup(to_box(t).reshape(-1, 3)).reshape(t.shape) & (delta > 0)
        rays = torch.arange(t.shape[0], device=t.device)[:, None].expand_as(t)
        return PackedSamples(rays[keep], t[keep], delta[keep])
