"""A scene: surfaces with materials and lights, rendered to linear HDR radiance and depth.

Radiance is baked per surface on first sight (:mod:`davis_io.emulator.shading`), then each view
is a ray cast (:mod:`davis_io.emulator.raytrace`) plus one bilinear lookup per pixel.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from davis_io.emulator.raytrace import PinholeCamera, Surface, nearest_hits
from davis_io.emulator.shading import Material, PointLight, RadianceAtlas, RadianceMap, bake

__all__ = ["TEXEL_M", "Scene"]

TEXEL_M = 0.006
"""Texel pitch of baked radiance, metres (about a pixel's footprint on the nearest surfaces)."""


@dataclass
class _Baked:
    maps: dict[int, RadianceMap] = field(default_factory=dict)
    atlas: RadianceAtlas | None = None


@dataclass(frozen=True)
class Scene:
    """A named analytic scene and where cameras should look at it from.

    Attributes:
        name: registry name.
        surfaces: quads and spheres.
        materials: one material per surface.
        lights: point lights (direct lighting, no shadows).
        ambient: RGB irradiance reaching every surface.
        background: RGB radiance of rays that hit nothing.
        camera_center: mean camera position for captures, metres.
        target: point the cameras look at, metres.
        baseline: spacing between neighbouring capture positions, metres.
    """

    name: str
    surfaces: tuple[Surface, ...]
    materials: tuple[Material, ...]
    lights: tuple[PointLight, ...]
    ambient: tuple[float, float, float]
    background: tuple[float, float, float]
    camera_center: tuple[float, float, float]
    target: tuple[float, float, float]
    baseline: float

    _baked: _Baked = field(default_factory=_Baked, init=False, repr=False, compare=False)

    def atlas(self, needed: np.ndarray) -> RadianceAtlas:
        """Baked radiance of at least the surfaces ``needed`` (each baked once, on first use)."""
        maps = self._baked.maps
        missing = [int(number) for number in needed if int(number) not in maps]
        for number in missing:
            maps[number] = bake(
                self.surfaces[number], self.materials[number], self.lights, self.ambient, TEXEL_M
            )
        if missing or self._baked.atlas is None:
            self._baked.atlas = RadianceAtlas(maps, len(self.surfaces), self.background)
        return self._baked.atlas

    def _hits(
        self, camera: PinholeCamera, c2w: np.ndarray
    ) -> tuple[RadianceAtlas, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Atlas, atlas entry and surface coordinates per pixel (flat), and depth ``(H, W)``."""
        index, depth, uv = nearest_hits(self.surfaces, camera, c2w)
        entry = index.ravel().astype(np.int64) + 1
        seen = np.flatnonzero(np.bincount(entry, minlength=len(self.surfaces) + 1)[1:])
        return self.atlas(seen), entry, uv[0].ravel(), uv[1].ravel(), depth

    def render(self, camera: PinholeCamera, c2w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear HDR radiance ``(H, W, 3)`` float32 and optical-axis depth ``(H, W)`` float32.

        Deterministic: the same camera and pose always give the same arrays.
        """
        atlas, entry, s, r, depth = self._hits(camera, c2w)
        radiance = atlas.lookup(entry, s, r)
        return radiance.reshape(camera.height, camera.width, 3), depth

    def render_channel(
        self, camera: PinholeCamera, c2w: np.ndarray, channel: np.ndarray
    ) -> np.ndarray:
        """Radiance ``(H, W)`` float32 of one channel per pixel, as a colour mosaic sees it.

        Args:
            camera: pinhole intrinsics.
            c2w: camera-to-world pose.
            channel: ``(H, W)`` int64: 0, 1, 2 for R, G, B and 3 for luminance.
        """
        atlas, entry, s, r, _ = self._hits(camera, c2w)
        values = atlas.lookup_channel(entry, s, r, channel.ravel())
        return values.reshape(camera.height, camera.width)
