"""Diffuse lighting baked into per-surface radiance maps, and their bilinear lookup at render time.

Surfaces are Lambertian (radiance does not depend on the view) and lights cast no shadows, so
each surface's outgoing radiance is a fixed function of its surface coordinates: it is evaluated
once on a grid of texels and then only looked up, which is what makes rendering fast.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from davis_io.colorfilter import LUMINANCE_WEIGHTS
from davis_io.emulator.raytrace import Surface
from davis_io.emulator.textures import Texture

__all__ = ["Material", "PointLight", "RadianceAtlas", "RadianceMap", "bake", "irradiance"]


@dataclass(frozen=True)
class Material:
    """How a surface looks: albedo times irradiance plus its own emission.

    Attributes:
        albedo: texture of the diffuse reflectance (0..1 per channel).
        emission: texture of emitted radiance (radiance units), or None for a non-emitter.
    """

    albedo: Texture
    emission: Texture | None = None


@dataclass(frozen=True)
class PointLight:
    """An isotropic point light: irradiance ``power * max(0, n.l) / distance**2`` (no shadows)."""

    position: tuple[float, float, float]
    power: tuple[float, float, float]


def irradiance(
    points: np.ndarray, normals: np.ndarray, lights: Sequence[PointLight], ambient: np.ndarray
) -> np.ndarray:
    """RGB irradiance ``(M, 3)`` at points ``(M, 3)`` with front normals ``(M, 3)``."""
    total = np.broadcast_to(np.asarray(ambient, np.float64), points.shape).copy()
    for light in lights:
        to_light = np.asarray(light.position) - points
        distance2 = np.einsum("ij,ij->i", to_light, to_light)
        cosine = np.maximum(np.einsum("ij,ij->i", normals, to_light), 0) / np.sqrt(distance2)
        total += np.outer(cosine / distance2, np.asarray(light.power))
    return total


@dataclass(frozen=True)
class RadianceMap:
    """Outgoing radiance of one surface sampled on a texel grid over its surface coordinates.

    Attributes:
        values: ``(rows, cols, 4)`` float32: radiance R, G, B and luminance (what a monochrome
            pixel sees); texel ``(i, j)`` is centred at surface coordinates
            ``(s_min + (j + 0.5) * texel_m, r_min + (i + 0.5) * texel_m)``.
        origin: ``(s_min, r_min)`` in metres.
        texel_m: texel pitch in metres.
    """

    values: np.ndarray
    origin: tuple[float, float]
    texel_m: float


class RadianceAtlas:
    """Radiance maps of many surfaces plus a background colour in one array.

    Entry 0 is the background; surface ``k`` is entry ``k + 1``. Each map is stored with one
    extra column and row repeating its edge, so bilinear lookups never leave it.
    """

    def __init__(
        self, maps: dict[int, RadianceMap], surface_count: int, background: Sequence[float]
    ) -> None:
        self.surfaces = frozenset(maps)
        count = surface_count + 1
        # Per entry: s_min, r_min, 1 / texel, last column, last row; first texel, row stride.
        self._origin_s, self._origin_r = np.zeros(count, np.float32), np.zeros(count, np.float32)
        self._inverse_texel = np.ones(count, np.float32)
        self._last_col, self._last_row = np.zeros(count, np.float32), np.zeros(count, np.float32)
        self._first, self._stride = np.zeros(count, np.int64), np.full(count, 2, np.int64)
        rgb = np.asarray(background, np.float32)
        chunks = [np.append(rgb, rgb @ LUMINANCE_WEIGHTS)[None].repeat(4, 0)]
        start = 4
        for number, radiance_map in sorted(maps.items()):
            rows, cols = radiance_map.values.shape[:2]
            entry = number + 1
            self._origin_s[entry], self._origin_r[entry] = radiance_map.origin
            self._inverse_texel[entry] = 1 / radiance_map.texel_m
            self._last_col[entry], self._last_row[entry] = cols - 1, rows - 1
            self._first[entry], self._stride[entry] = start, cols + 1
            padded = np.pad(radiance_map.values, ((0, 1), (0, 1), (0, 0)), mode="edge")
            chunks.append(padded.reshape(-1, 4))
            start += padded.shape[0] * padded.shape[1]
        self._values = np.concatenate(chunks)

    def _texel_position(
        self, coordinate: np.ndarray, entry: np.ndarray, origin: np.ndarray, last: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        position = (coordinate - origin[entry]) * self._inverse_texel[entry] - np.float32(0.5)
        np.clip(position, 0, last[entry], out=position)
        whole = np.floor(position)
        return whole.astype(np.int64), position - whole

    def _corners(
        self, entry: np.ndarray, s: np.ndarray, r: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        col, fu = self._texel_position(s, entry, self._origin_s, self._last_col)
        row, fv = self._texel_position(r, entry, self._origin_r, self._last_row)
        stride = self._stride[entry]
        return self._first[entry] + row * stride + col, stride, fu, fv

    def lookup(self, entry: np.ndarray, s: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Bilinear radiance ``(M, 3)`` of atlas entries ``(M,)`` at coordinates ``s``, ``r``.

        Coordinates outside a map take the value of its nearest edge texel.
        """
        first, stride, fu, fv = self._corners(entry, s, r)
        fu, fv = fu[:, None], fv[:, None]
        below = first + stride
        top_left = np.take(self._values, first, axis=0)
        top = top_left + (np.take(self._values, first + 1, axis=0) - top_left) * fu
        bottom_left = np.take(self._values, below, axis=0)
        bottom = bottom_left + (np.take(self._values, below + 1, axis=0) - bottom_left) * fu
        return (top + (bottom - top) * fv)[:, :3]

    def lookup_channel(
        self, entry: np.ndarray, s: np.ndarray, r: np.ndarray, channel: np.ndarray
    ) -> np.ndarray:
        """Bilinear radiance ``(M,)`` of one channel per pixel (0..2 R, G, B; 3 luminance)."""
        first, stride, fu, fv = self._corners(entry, s, r)
        flat = self._values.reshape(-1)
        index = first * 4 + channel
        below = index + stride * 4
        top_left = np.take(flat, index)
        top = top_left + (np.take(flat, index + 4) - top_left) * fu
        bottom_left = np.take(flat, below)
        bottom = bottom_left + (np.take(flat, below + 4) - bottom_left) * fu
        return top + (bottom - top) * fv


def bake(
    surface: Surface,
    material: Material,
    lights: Sequence[PointLight],
    ambient: Sequence[float],
    texel_m: float,
) -> RadianceMap:
    """Evaluate a surface's outgoing radiance on its texel grid.

    Args:
        surface: the geometry (its ``uv_bounds`` set the grid).
        material: albedo and emission textures.
        lights: point lights.
        ambient: RGB ambient irradiance.
        texel_m: texel pitch in metres (about the footprint of a pixel on the nearest views).

    Returns:
        The radiance map, float32.
    """
    s_min, s_max, r_min, r_max = surface.uv_bounds
    cols = max(1, int(np.ceil((s_max - s_min) / texel_m)))
    rows = max(1, int(np.ceil((r_max - r_min) / texel_m)))
    grid_r, grid_s = np.mgrid[0:rows, 0:cols]
    uv = np.stack(
        [s_min + (grid_s.ravel() + 0.5) * texel_m, r_min + (grid_r.ravel() + 0.5) * texel_m], 1
    ).astype(np.float32)
    points, normals = surface.points_at(uv)
    radiance = material.albedo(uv) * irradiance(points, normals, lights, np.asarray(ambient))
    if material.emission is not None:
        radiance = radiance + material.emission(uv)
    values = np.empty((rows, cols, 4), np.float32)
    values[..., :3] = radiance.reshape(rows, cols, 3)
    values[..., 3] = values[..., :3] @ LUMINANCE_WEIGHTS
    return RadianceMap(values, (float(s_min), float(r_min)), float(texel_m))
