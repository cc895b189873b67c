"""How many samples a ray gets, and where: the sampler a preset names (plain data, no torch)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SamplerSpec"]


@dataclass(frozen=True)
class SamplerSpec:
    """Where rays are sampled.

    Attributes:
        kind: ``hierarchical`` (stratified coarse field, then importance samples for a fine field)
            or ``occupancy`` (stratified candidates, kept only in occupied grid cells).
        coarse: stratified samples (hierarchical) or candidates (occupancy) per ray.
        fine: importance samples per ray. With ``occupancy`` and ``fine > 0`` the candidates'
            densities are computed without gradients and only ``fine`` samples drawn from them
            are shaded (a proposal pass through the same field).
        grid_resolution: occupancy cells per side.
        render_coarse: candidates per ray when rendering views (0: ``coarse``).
        render_fine: shaded samples per ray when rendering views (0: ``fine``).
        density_noise: std of Gaussian noise added to raw density while training (reference 1.0).
    """

    kind: str = "occupancy"
    coarse: int = 128
    fine: int = 0
    grid_resolution: int = 64
    density_noise: float = 0.0
    render_coarse: int = 0
    render_fine: int = 0

    def counts(self, training: bool) -> tuple[int, int]:
        """``(coarse, fine)`` sample counts for training or for rendering views."""
        if training:
            return self.coarse, self.fine
        return self.render_coarse or self.coarse, self.render_fine or self.fine
