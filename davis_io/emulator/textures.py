"""Procedural, deterministic surface textures (value noise, tiles, stripes, spots), numpy only.

Every texture maps ``(M, 2)`` surface coordinates in metres to ``(M, 3)`` float32 linear RGB
factors; the same coordinates always give the same values, whatever the view. Randomness comes
from seeded 256 x 256 lattices of uniform values, so patterns repeat every 256 cells.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache

import numpy as np

__all__ = [
    "Texture",
    "fbm",
    "hash01",
    "scaled",
    "stripes",
    "textured_color",
    "tiles",
    "with_dots",
]

Texture = Callable[[np.ndarray], np.ndarray]
"""Maps ``(M, 2)`` surface coordinates in metres to ``(M, 3)`` linear RGB factors."""

_PERIOD = 256


@cache
def _lattice(seed: int) -> np.ndarray:
    return np.random.default_rng([seed, 0x7E47]).random((_PERIOD, _PERIOD), np.float32)


def hash01(ix: np.ndarray, iy: np.ndarray, seed: int) -> np.ndarray:
    """Pseudo-random float32 in [0, 1) per integer lattice point, periodic every 256 cells."""
    row = np.asarray(iy).astype(np.int64, copy=False) & (_PERIOD - 1)
    column = np.asarray(ix).astype(np.int64, copy=False) & (_PERIOD - 1)
    return np.take(_lattice(seed), row * _PERIOD + column)


def _value_noise(uv: np.ndarray, seed: int) -> np.ndarray:
    cell = np.floor(uv)
    frac = (uv - cell).astype(np.float32)
    across, down = (
        frac[:, 0] * frac[:, 0] * (3 - 2 * frac[:, 0]),
        frac[:, 1] * frac[:, 1] * (3 - 2 * frac[:, 1]),
    )
    ix, iy = cell[:, 0].astype(np.int64), cell[:, 1].astype(np.int64)
    top = hash01(ix, iy, seed)
    top += (hash01(ix + 1, iy, seed) - top) * across
    bottom = hash01(ix, iy + 1, seed)
    bottom += (hash01(ix + 1, iy + 1, seed) - bottom) * across
    return top + (bottom - top) * down


def fbm(uv: np.ndarray, scale: float, seed: int, octaves: int = 4) -> np.ndarray:
    """Fractal value noise in [0, 1): ``octaves`` layers, each twice as fine and half as strong.

    Args:
        uv: ``(M, 2)`` surface coordinates, metres.
        scale: size of the coarsest blobs, metres.
        seed: selects the pattern.
        octaves: number of layers.
    """
    total = np.zeros(len(uv), np.float32)
    weight_sum = 0.0
    for octave in range(octaves):
        weight = 0.5**octave
        total += weight * _value_noise(uv * (2**octave / scale), seed + 7919 * octave)
        weight_sum += weight
    return total / np.float32(weight_sum)


def textured_color(color: Sequence[float], *, scale: float, contrast: float, seed: int) -> Texture:
    """A colour modulated by fractal noise: ``color * (1 - contrast + 2 * contrast * fbm)``."""
    rgb = np.asarray(color, np.float32)

    def texture(uv: np.ndarray) -> np.ndarray:
        factor = 1 - contrast + 2 * contrast * fbm(uv, scale, seed)
        return factor[:, None] * rgb

    return texture


def tiles(
    palette: Sequence[Sequence[float]],
    *,
    cell: float,
    grout: float,
    grout_color: Sequence[float],
    seed: int,
) -> Texture:
    """Square tiles, each a palette colour picked by hash and shaded by noise, with dark grout.

    Args:
        palette: ``(K, 3)`` tile colours (albedo or emission factors).
        cell: tile pitch, metres.
        grout: grout line width, metres.
        grout_color: RGB of the grout lines.
        seed: selects colours and noise.
    """
    colors = np.asarray(palette, np.float32)
    grout_rgb = np.asarray(grout_color, np.float32)

    def texture(uv: np.ndarray) -> np.ndarray:
        index = np.floor(uv / cell)
        pick = hash01(index[:, 0], index[:, 1], seed)
        rgb = colors[np.minimum((pick * len(colors)).astype(np.int64), len(colors) - 1)]
        rgb = rgb * (0.7 + 0.6 * fbm(uv, cell / 3, seed + 1))[:, None]
        edge = np.min(np.abs(uv - np.round(uv / cell) * cell), axis=1) < grout / 2
        return np.where(edge[:, None], grout_rgb, rgb).astype(np.float32)

    return texture


def stripes(
    color_a: Sequence[float], color_b: Sequence[float], *, period: float, axis: int, seed: int
) -> Texture:
    """Irregular stripes along one surface axis, alternating two colours, with noisy widths."""
    rgb_a, rgb_b = np.asarray(color_a, np.float32), np.asarray(color_b, np.float32)

    def texture(uv: np.ndarray) -> np.ndarray:
        warp = uv[:, axis] / period + 0.6 * fbm(uv, period * 4, seed)
        band = (np.floor(warp) % 2 == 0)[:, None]
        shade = (0.75 + 0.5 * fbm(uv, period / 2, seed + 3))[:, None]
        return np.where(band, rgb_a, rgb_b) * shade

    return texture


def with_dots(
    texture: Texture, palette: Sequence[Sequence[float]], *, cell: float, seed: int
) -> Texture:
    """The texture with round spots (good blobs for feature matching).

    In two of three cells of a ``cell`` grid lies a disc of random position, radius (0.12..0.3
    cells) and palette colour.
    """
    colors = np.asarray(palette, np.float32)

    def result(uv: np.ndarray) -> np.ndarray:
        base = texture(uv)
        index = np.floor(uv / cell)
        local = uv / cell - index
        ix, iy = index[:, 0], index[:, 1]
        center = np.stack(
            [0.3 + 0.4 * hash01(ix, iy, seed + 1), 0.3 + 0.4 * hash01(ix, iy, seed + 2)], 1
        )
        radius = 0.12 + 0.18 * hash01(ix, iy, seed + 3)
        present = hash01(ix, iy, seed + 4) < 2 / 3
        inside = present & (np.sum((local - center) ** 2, axis=1) < radius**2)
        pick = np.minimum(
            (hash01(ix, iy, seed + 5) * len(colors)).astype(np.int64), len(colors) - 1
        )
        return np.where(inside[:, None], colors[pick], base)

    return result


def scaled(texture: Texture, level: float) -> Texture:
    """The texture multiplied by a constant (for example an emitter's radiance level)."""

    def result(uv: np.ndarray) -> np.ndarray:
        return texture(uv) * np.float32(level)

    return result
