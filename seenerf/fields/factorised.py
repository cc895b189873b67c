"""A factorised (vector-matrix) field for CPUs: three feature planes times three feature lines."""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import nn

__all__ = ["CHANNELS_PER_LOOKUP", "VectorMatrixField", "sample_vector_matrix"]

_PLANE_AXES = ([0, 1], [0, 2], [1, 2])
_LINE_AXIS = [2, 1, 0]

CHANNELS_PER_LOOKUP = 4
"""Feature channels one batch entry of a lookup reads (where they divide the factor's channels).

``grid_sample``'s CPU gradient scatters every channel of an entry into its whole plane and
gives each thread whole entries. As three planes of 16 channels, three entries kept one of two
threads half idle and each plane's gradient (2.4 MB at 192²) out of a core's cache. Split four
channels to an entry, the forward and backward of one such lookup at 30,720 points took 14-16
ms against 18-26 ms on two threads and 26-35 ms against 41 ms on one (medians of 15, two runs).
The values and gradients are the same: a fit's loss trajectory is unchanged.
"""


def sample_vector_matrix(
    planes: torch.Tensor, lines: torch.Tensor, points: torch.Tensor
) -> torch.Tensor:
    """Sum over the three axis pairs of plane(u, v) * line(w), bilinear/linear interpolated.

    Args:
        planes: ``(3, C, N, N)`` features on the xy, xz and yz planes.
        lines: ``(3, C, N, 1)`` features along z, y and x.
        points: ``(P, 3)`` box coordinates in ``[-1, 1]``.

    Returns:
        ``(P, C)`` features.
    """
    plane_uv = torch.stack([points[:, axes] for axes in _PLANE_AXES])
    line_w = points[:, _LINE_AXIS].T
    line_uv = torch.stack([torch.zeros_like(line_w), line_w], dim=-1)
    return (_lookup(planes, plane_uv) * _lookup(lines, line_uv)).sum(dim=0).T


def _lookup(features: torch.Tensor, uv: torch.Tensor) -> torch.Tensor:
    """Bilinear lookup of ``(3, C, H, W)`` features at ``(3, P, 2)`` coordinates: ``(3, C, P)``.

    The channels are looked up :data:`CHANNELS_PER_LOOKUP` at a time, each group a batch entry
    of its own with its factor's coordinates.
    """
    factors, channels, height, width = features.shape
    groups = channels // CHANNELS_PER_LOOKUP if channels % CHANNELS_PER_LOOKUP == 0 else 1
    grouped = features.reshape(factors * groups, channels // groups, height, width)
    coordinates = uv.repeat_interleave(groups, dim=0)[:, None]
    looked_up = F.grid_sample(grouped, coordinates, align_corners=True)
    return looked_up.reshape(factors, channels, -1)


class _SquaredSteps(torch.autograd.Function):
    """Sum over the last two axes of the mean squared difference of neighbouring texels.

    The gradient is written out (each difference added to one neighbour and taken from the
    other) instead of autograd's slice copies: a third of the time on a field's texels.
    """

    @staticmethod
    def forward(ctx, factor: torch.Tensor) -> torch.Tensor:
        ctx.save_for_backward(factor)
        total = factor.new_zeros(())
        for dim in (-2, -1):
            if factor.shape[dim] > 1:
                steps = factor.diff(dim=dim).flatten()
                total = total + torch.dot(steps, steps) / steps.numel()
        return total

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> torch.Tensor:
        (factor,) = ctx.saved_tensors
        result = torch.zeros_like(factor)
        for dim in (-2, -1):
            length = factor.shape[dim]
            if length > 1:
                steps = factor.diff(dim=dim)
                steps.mul_(2.0 * grad / steps.numel())
                result.narrow(dim, 1, length - 1).add_(steps)
                result.narrow(dim, 0, length - 1).sub_(steps)
        return result


def _factors(channels: int, resolution: int, generator: torch.Generator, scale: float):
    planes = scale * torch.randn(3, channels, resolution, resolution, generator=generator)
    lines = scale * torch.randn(3, channels, resolution, 1, generator=generator)
    return nn.Parameter(planes), nn.Parameter(lines)


class VectorMatrixField(nn.Module):
    """Density and log radiance from vector-matrix factorised features and a tiny decoder.

    Density and appearance have separate factors, so density alone (for the occupancy grid and
    the first rendering stage) costs a fraction of a full query.

    Args:
        resolution: plane side and line length N, sized from the scene and the sensor.
        density_rank: feature channels of the density.
        appearance_rank: feature channels feeding the radiance decoder.
        hidden: width of the radiance decoder's hidden layer.
    """

    def __init__(
        self,
        resolution: int = 128,
        density_rank: int = 8,
        appearance_rank: int = 24,
        hidden: int = 64,
    ):
        super().__init__()
        generator = torch.Generator().manual_seed(0)
        self.density_planes, self.density_lines = _factors(density_rank, resolution, generator, 0.1)
        self.appearance_planes, self.appearance_lines = _factors(
            appearance_rank, resolution, generator, 0.1
        )
        self.decoder = nn.Sequential(
            nn.Linear(appearance_rank, hidden), nn.ReLU(), nn.Linear(hidden, 3)
        )

    def density(self, points: torch.Tensor) -> torch.Tensor:
        """Density ``(P,)`` per box unit at box points ``(P, 3)``."""
        features = sample_vector_matrix(self.density_planes, self.density_lines, points)
        return F.softplus(features.sum(-1) * 10.0 - 3.0)

    def radiance(self, points: torch.Tensor, directions: torch.Tensor) -> torch.Tensor:
        """Log radiance ``(P, 3)``; ``directions`` is unused (diffuse surfaces)."""
        del directions
        return self.decoder(
            sample_vector_matrix(self.appearance_planes, self.appearance_lines, points)
        )

    def forward(
        self, points: torch.Tensor, directions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Density ``(P,)`` and log radiance ``(P, 3)``."""
        return self.density(points), self.radiance(points, directions)

    def smoothness(self) -> torch.Tensor:
        """Mean squared difference of neighbouring plane and line texels (total variation)."""
        factors = (
            self.density_planes,
            self.density_lines,
            self.appearance_planes,
            self.appearance_lines,
        )
        return sum(_SquaredSteps.apply(factor) for factor in factors)
