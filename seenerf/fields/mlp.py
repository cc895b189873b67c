"""The published See-NeRF field: positional encoding and an 8x256 MLP with a skip at layer 4."""

from __future__ import annotations

import torch
from torch import nn

__all__ = ["PaperField", "positional_encoding"]


def positional_encoding(x: torch.Tensor, num_frequencies: int) -> torch.Tensor:
    """``[x, sin(2^0 x), cos(2^0 x), ..., sin(2^(L-1) x), cos(2^(L-1) x)]`` (no pi factor).

    Args:
        x: ``(N, D)`` input.
        num_frequencies: L.

    Returns:
        ``(N, D * (1 + 2 L))``.
    """
    frequencies = 2.0 ** torch.arange(num_frequencies, dtype=x.dtype, device=x.device)
    scaled = (x[..., None, :] * frequencies[:, None]).flatten(-2)
    return torch.cat([x, torch.sin(scaled), torch.cos(scaled)], dim=-1)


class PaperField(nn.Module):
    """NeRF MLP: density from position, log radiance (no activation) from position and view.

    Args:
        depth: number of 256-wide layers (8).
        width: layer width (256).
        position_frequencies: L for xyz (10).
        direction_frequencies: L for the view direction (4).
        skip_layer: layer index whose input is re-concatenated with the encoding (4).
    """

    def __init__(
        self,
        depth: int = 8,
        width: int = 256,
        position_frequencies: int = 10,
        direction_frequencies: int = 4,
        skip_layer: int = 4,
    ):
        super().__init__()
        self.position_frequencies = position_frequencies
        self.direction_frequencies = direction_frequencies
        self.skip_layer = skip_layer
        position_dims = 3 * (1 + 2 * position_frequencies)
        direction_dims = 3 * (1 + 2 * direction_frequencies)
        layers = []
        for index in range(depth):
            inputs = position_dims if index == 0 else width
            if index == skip_layer + 1:
                inputs += position_dims
            layers.append(nn.Linear(inputs, width))
        self.layers = nn.ModuleList(layers)
        self.density_head = nn.Linear(width, 1)
        self.feature = nn.Linear(width, width)
        self.view_layer = nn.Linear(width + direction_dims, width // 2)
        self.radiance_head = nn.Linear(width // 2, 3)

    def _trunk(self, points: torch.Tensor) -> torch.Tensor:
        hidden = encoded = positional_encoding(points, self.position_frequencies)
        for index, layer in enumerate(self.layers):
            if index == self.skip_layer + 1:
                hidden = torch.cat([encoded, hidden], dim=-1)
            hidden = torch.relu(layer(hidden))
        return hidden

    def forward(
        self, points: torch.Tensor, directions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Density ``(N,)`` (>= 0, per box unit) and log radiance ``(N, 3)``."""
        hidden = self._trunk(points)
        density = torch.relu(self.density_head(hidden)).squeeze(-1)
        view = positional_encoding(directions, self.direction_frequencies)
        hidden = torch.relu(self.view_layer(torch.cat([self.feature(hidden), view], dim=-1)))
        return density, self.radiance_head(hidden)

    def density(self, points: torch.Tensor) -> torch.Tensor:
        """Density ``(N,)`` alone (the radiance branch is skipped)."""
        return torch.relu(self.density_head(self._trunk(points))).squeeze(-1)
