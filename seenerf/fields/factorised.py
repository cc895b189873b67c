"""A factorised (vector-matrix) field for CPUs: three feature planes times three feature lines."""

from __future__ import annotations

import torch
import torch.nn.functional as F  # noqa: N812
from torch import nn

__all__ = ["VectorMatrixField", "sample_vector_matrix"]

_PLANE_AXES = ([0, 1], [0, 2], [1, 2])
_LINE_AXIS = [2, 1, 0]


def sample_vector_matrix(
    planes: list[torch.Tensor], lines: list[torch.Tensor], points: torch.Tensor
) -> torch.Tensor:
    """Sum over the three axis pairs of plane(u, v) * line(w), bilinear/linear interpolated.

    Args:
        planes: features on the xy, xz and yz planes, ``(C, Ny, Nx)``, ``(C, Nz, Nx)`` and
            ``(C, Nz, Ny)``.
        lines: features along z, y and x, ``(C, Nz, 1)``, ``(C, Ny, 1)`` and ``(C, Nx, 1)``.
        points: ``(P, 3)`` box coordinates in ``[-1, 1]``.

    Returns:
        ``(P, C)`` features.
    """
    features = None
    for plane, line, axes, axis in zip(planes, lines, _PLANE_AXES, _LINE_AXIS, strict=True):
        plane_uv = points[None, None, :, axes]
        w = points[:, axis]
        line_uv = torch.stack([torch.zeros_like(w), w], dim=-1)[None, None]
        product = F.grid_sample(plane[None], plane_uv, align_corners=True) * F.grid_sample(
            line[None], line_uv, align_corners=True
        )
        features = product if features is None else features + product
    return features[0, :, 0].T


def _factors(
    channels: int, resolution: tuple[int, int, int], generator: torch.Generator, scale: float
) -> tuple[nn.ParameterList, nn.ParameterList]:
    nx, ny, nz = resolution
    plane_shapes = ((ny, nx), (nz, nx), (nz, ny))
    line_lengths = (nz, ny, nx)
    planes = [scale * torch.randn(channels, *shape, generator=generator) for shape in plane_shapes]
    lines = [scale * torch.randn(channels, n, 1, generator=generator) for n in line_lengths]
    return nn.ParameterList(planes), nn.ParameterList(lines)


def _squared_steps(factor: torch.Tensor) -> torch.Tensor:
    """Mean squared difference of neighbouring texels along each spatial axis, summed."""
    total = (factor[:, 1:] - factor[:, :-1]).square().mean()
    if factor.shape[-1] > 1:
        total = total + (factor[..., 1:] - factor[..., :-1]).square().mean()
    return total


class VectorMatrixField(nn.Module):
    """Density and log radiance from vector-matrix factorised features and a tiny decoder.

    Density and appearance have separate factors, so density alone (for the occupancy grid and
    the first rendering stage) costs a fraction of a full query.

    Args:
        resolution: texels along x, y and z (one number: the same along all three), sized from
            the scene and the sensor.
        density_rank: feature channels of the density.
        appearance_rank: feature channels feeding the radiance decoder.
        hidden: width of the radiance decoder's hidden layer.
    """

    def __init__(
        self,
        resolution: int | tuple[int, int, int] | list[int] = 128,
        density_rank: int = 8,
        appearance_rank: int = 24,
        hidden: int = 64,
    ):
        super().__init__()
        sides = (resolution,) * 3 if isinstance(resolution, int) else tuple(resolution)
        generator = torch.Generator().manual_seed(0)
        self.density_planes, self.density_lines = _factors(density_rank, sides, generator, 0.1)
        self.appearance_planes, self.appearance_lines = _factors(
            appearance_rank, sides, generator, 0.1
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
        """Total variation: mean squared difference of neighbouring texels.

        Averaged over the three planes and over the three lines, of density and of appearance.
        """
        total = self.density_planes[0].new_zeros(())
        for planes, lines in (
            (self.density_planes, self.density_lines),
            (self.appearance_planes, self.appearance_lines),
        ):
            total = total + sum(_squared_steps(plane) for plane in planes) / 3.0
            total = total + sum(_squared_steps(line) for line in lines) / 3.0
        return total
