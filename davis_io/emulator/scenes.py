"""Built-in analytic HDR scenes: textured rooms lit by lamps and windows, with dark corners.

World axes follow the cameras' OpenCV axes: x right, y down, z away from the cameras, in metres.
Radiance units: 1.0 is the radiance that the training exposure maps to the response curve's input
1 (see :mod:`davis_io.emulator.response`); a mid-grey surface under the main light is about 0.2,
lamps and windows are 20..200, the darkest corners about 1e-3. Every scene spans more than
10^4 between its brightest and darkest textured surfaces.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache

import numpy as np

from davis_io.emulator.raytrace import Sphere, Surface, box_faces
from davis_io.emulator.scene import Scene
from davis_io.emulator.shading import Material, PointLight
from davis_io.emulator.textures import Texture, scaled, stripes, textured_color, tiles, with_dots
from davis_io.errors import UsageError

__all__ = ["SCENES", "corridor", "get_scene", "lamp", "room"]

Rgb = Sequence[float]
Palette = Sequence[Rgb]
Point = Sequence[float]

_WARM_PALETTE = [(0.55, 0.35, 0.2), (0.7, 0.65, 0.5), (0.25, 0.35, 0.5), (0.6, 0.2, 0.15)]
_COOL_PALETTE = [(0.2, 0.4, 0.45), (0.5, 0.55, 0.6), (0.15, 0.2, 0.3), (0.65, 0.6, 0.4)]
_DARK_PALETTE = [(0.03, 0.03, 0.035), (0.06, 0.05, 0.04), (0.02, 0.025, 0.03)]
_SPOT_PALETTE = [(0.8, 0.78, 0.7), (0.05, 0.05, 0.06), (0.6, 0.15, 0.1), (0.1, 0.3, 0.55)]


def _matte(texture: Texture, *, spots: float = 0.0, seed: int = 0) -> Material:
    """A non-emitting material; ``spots`` > 0 adds round spots on a grid of that pitch (m)."""
    if spots > 0:
        texture = with_dots(texture, _SPOT_PALETTE, cell=spots, seed=seed)
    return Material(albedo=texture)


def _spotted(color: Rgb, *, scale: float, contrast: float, seed: int) -> Material:
    """Noise-textured colour with darker and lighter spots (blobs for feature matching)."""
    base = np.asarray(color)
    palette = [base * 0.25, np.minimum(base * 2.0, 0.9), base[::-1]]
    spotted = with_dots(
        textured_color(color, scale=scale, contrast=contrast, seed=seed),
        palette,
        cell=scale * 0.6,
        seed=seed + 100,
    )
    return Material(albedo=spotted)


def _lamp(level: float, color: Rgb, seed: int) -> Material:
    glow = textured_color(color, scale=0.06, contrast=0.5, seed=seed)
    return Material(
        albedo=textured_color((0.8, 0.8, 0.8), scale=0.1, contrast=0.1, seed=seed),
        emission=scaled(glow, level),
    )


def _box(low: Point, high: Point, material: Material) -> list[tuple[Surface, Material]]:
    return [(face, material) for face in box_faces(low, high)]


def _room(low: Point, high: Point, materials: Sequence[Material]) -> list[tuple[Surface, Material]]:
    return list(zip(box_faces(low, high, inward=True), materials, strict=True))


def _scene(name: str, parts: list[tuple[Surface, Material]], **settings) -> Scene:
    surfaces, materials = zip(*parts, strict=True)
    return Scene(name, tuple(surfaces), tuple(materials), **settings)


def _tiled(
    palette: Palette, cell: float, grout_grey: float, seed: int, spots: float = 0.0
) -> Material:
    """Tiles with 3 cm grout (2 cm below 25 cm cells) and spots every 1.7 cells by default."""
    grout = 0.03 if cell >= 0.25 else 0.02 if cell >= 0.12 else 0.015
    texture = tiles(palette, cell=cell, grout=grout, grout_color=(grout_grey,) * 3, seed=seed)
    return _matte(texture, spots=spots or 1.7 * cell, seed=seed + 200)


def _striped(color_a: Rgb, color_b: Rgb, period: float, axis: int, seed: int) -> Material:
    """Noisy stripes with spots every 2.5 periods."""
    texture = stripes(color_a, color_b, period=period, axis=axis, seed=seed)
    return _matte(texture, spots=2.5 * period, seed=seed + 200)


def room() -> Scene:
    """A living room: tiled back wall, wooden floor, a bright lamp, a dark cabinet in a corner."""
    walls = [
        _spotted((0.04, 0.035, 0.03), scale=0.3, contrast=0.6, seed=11),
        _spotted((0.45, 0.42, 0.38), scale=0.25, contrast=0.5, seed=12),
        _spotted((0.6, 0.6, 0.58), scale=0.4, contrast=0.3, seed=13),
        _striped((0.35, 0.22, 0.12), (0.22, 0.13, 0.07), 0.15, 1, seed=14),
        _spotted((0.3, 0.3, 0.3), scale=0.3, contrast=0.4, seed=15),
        _tiled(_WARM_PALETTE, 0.35, 0.08, seed=16),
    ]
    parts = _room((-3.0, -1.8, -1.0), (3.0, 1.2, 6.5), walls)
    parts += _box((-0.9, 0.45, 3.0), (0.5, 1.2, 4.0), _tiled(_COOL_PALETTE, 0.2, 0.05, seed=21))
    parts += _box((-3.0, -0.9, 5.0), (-1.9, 1.2, 6.5), _tiled(_DARK_PALETTE, 0.25, 0.01, seed=22))
    parts += _box(
        (1.0, 0.1, 4.8),
        (2.3, 1.2, 5.8),
        _striped((0.6, 0.5, 0.3), (0.15, 0.3, 0.4), 0.12, 0, seed=23),
    )
    parts += [
        (
            Sphere((-1.3, 0.7, 2.6), 0.5),
            _striped((0.7, 0.7, 0.65), (0.5, 0.1, 0.1), 0.1, 1, seed=24),
        ),
        (Sphere((1.55, -0.55, 4.4), 0.25), _lamp(80.0, (1.0, 0.85, 0.6), seed=25)),
    ]
    lights = (
        PointLight((1.55, -0.55, 4.4), (5.0, 4.2, 3.0)),
        PointLight((0.0, -1.6, 1.0), (0.35, 0.35, 0.4)),
    )
    return _scene(
        "room",
        parts,
        lights=lights,
        ambient=(0.004, 0.004, 0.005),
        background=(0.001,) * 3,
        camera_center=(0.0, -0.1, 0.0),
        target=(0.0, 0.2, 4.0),
        baseline=0.12,
    )


def lamp() -> Scene:
    """A desk at night: books and a globe under a glaring desk lamp, a dark wall behind."""
    walls = [
        _spotted((0.05, 0.05, 0.06), scale=0.3, contrast=0.6, seed=31),
        _spotted((0.08, 0.06, 0.05), scale=0.3, contrast=0.6, seed=32),
        _spotted((0.2, 0.2, 0.2), scale=0.4, contrast=0.3, seed=33),
        _spotted((0.1, 0.1, 0.1), scale=0.3, contrast=0.5, seed=34),
        _spotted((0.2, 0.2, 0.2), scale=0.3, contrast=0.4, seed=35),
        _tiled(_DARK_PALETTE + _COOL_PALETTE[:2], 0.3, 0.01, seed=36),
    ]
    parts = _room((-2.5, -1.8, -1.0), (2.5, 1.6, 5.0), walls)
    parts += _box(
        (-1.8, 0.6, 1.6),
        (1.8, 0.7, 4.6),
        _striped((0.45, 0.3, 0.15), (0.3, 0.18, 0.08), 0.06, 1, seed=41),
    )
    parts += _box(
        (-1.2, 0.1, 3.2),
        (-0.6, 0.6, 3.6),
        _striped((0.6, 0.1, 0.1), (0.8, 0.75, 0.6), 0.05, 1, seed=42),
    )
    parts += _box((-0.5, 0.3, 2.6), (0.2, 0.6, 3.1), _tiled(_WARM_PALETTE, 0.1, 0.05, seed=43))
    parts += _box((1.15, -0.75, 3.7), (1.55, -0.55, 4.1), _lamp(150.0, (1.0, 0.95, 0.8), seed=45))
    parts += _box(
        (1.3, -0.55, 3.85),
        (1.4, 0.6, 3.95),
        _matte(textured_color((0.1, 0.1, 0.1), scale=0.05, contrast=0.5, seed=46)),
    )
    parts += [(Sphere((0.7, 0.25, 3.4), 0.35), _tiled(_COOL_PALETTE, 0.15, 0.7, seed=44))]
    lights = (PointLight((1.35, -0.45, 3.9), (3.0, 2.8, 2.3)),)
    return _scene(
        "lamp",
        parts,
        lights=lights,
        ambient=(0.003, 0.003, 0.004),
        background=(0.001,) * 3,
        camera_center=(0.0, -0.2, 0.0),
        target=(0.0, 0.3, 3.3),
        baseline=0.1,
    )


def corridor() -> Scene:
    """A long corridor with pillars and door frames, ending at a bright window."""
    sky = textured_color((0.75, 0.85, 1.0), scale=0.35, contrast=0.45, seed=57)
    window = Material(
        albedo=textured_color((0.5,) * 3, scale=1.0, contrast=0.1, seed=56),
        emission=scaled(sky, 60.0),
    )
    walls = [
        _tiled(_COOL_PALETTE, 0.3, 0.05, seed=51, spots=0.3),
        _spotted((0.3, 0.28, 0.25), scale=0.2, contrast=0.6, seed=52),
        _spotted((0.5, 0.5, 0.5), scale=0.3, contrast=0.3, seed=53),
        _tiled(_WARM_PALETTE, 0.4, 0.1, seed=54, spots=0.35),
        _spotted((0.05, 0.05, 0.05), scale=0.3, contrast=0.5, seed=55),
        window,
    ]
    parts = _room((-1.4, -1.5, -1.0), (1.4, 1.2, 14.0), walls)
    pillar = _striped((0.5, 0.45, 0.4), (0.2, 0.18, 0.16), 0.1, 1, seed=61)
    frame = _tiled(_DARK_PALETTE, 0.12, 0.2, seed=62)
    parts += _box((-1.4, -1.5, 3.0), (-1.0, 1.2, 3.4), pillar)
    parts += _box((1.0, -1.5, 5.0), (1.4, 1.2, 5.4), pillar)
    parts += _box((-1.4, -1.5, 8.0), (-1.1, 1.2, 8.3), frame)
    parts += _box((-0.05, -1.5, 13.9), (0.05, 1.2, 13.99), frame)
    parts += _box((-1.4, -0.3, 13.9), (1.4, -0.2, 13.99), frame)
    parts += _box((-0.4, 0.5, 2.2), (0.3, 1.2, 2.9), _tiled(_WARM_PALETTE, 0.12, 0.05, seed=63))
    parts += [
        (
            Sphere((0.6, 0.85, 6.0), 0.35),
            _striped((0.7, 0.6, 0.2), (0.1, 0.1, 0.3), 0.08, 0, seed=64),
        )
    ]
    lights = (
        PointLight((0.0, -0.2, 13.0), (40.0, 44.0, 50.0)),
        PointLight((0.0, -1.3, 2.0), (0.6, 0.55, 0.45)),
        PointLight((0.0, -1.3, 6.5), (0.8, 0.75, 0.6)),
    )
    return _scene(
        "corridor",
        parts,
        lights=lights,
        ambient=(0.002, 0.002, 0.0025),
        background=(0.001,) * 3,
        camera_center=(0.0, -0.1, 0.0),
        target=(0.0, -0.1, 7.0),
        baseline=0.1,
    )


SCENES: dict[str, Callable[[], Scene]] = {"room": room, "lamp": lamp, "corridor": corridor}
"""Built-in scenes by name."""


@cache
def get_scene(name: str) -> Scene:
    """The built-in scene called ``name`` (built once per process; scenes are immutable).

    Raises:
        UsageError: no scene has that name.
    """
    if name not in SCENES:
        raise UsageError(f"unknown emulator scene {name!r}; choose one of {', '.join(SCENES)}")
    return SCENES[name]()
