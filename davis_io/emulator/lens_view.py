"""What a camera with a distorted lens sees: a wider pinhole view, resampled through the lens.

The ray caster is a pinhole (:mod:`davis_io.emulator.raytrace`). A lens with distortion sends
pixel ``(u, v)`` along the ray of its undistorted normalised coordinates; the view renders a
pinhole of the same focal lengths wide enough to hold every such ray and samples it there
(bilinear radiance, nearest depth).
"""

from __future__ import annotations

from functools import cached_property

import cv2
import numpy as np

from davis_io.emulator.raytrace import PinholeCamera
from davis_io.errors import UsageError
from davis_io.lens import Lens

__all__ = ["LensView", "lens_distortion"]

_RANDOM_K1 = (-0.35, -0.08)
"""Range of ``k1`` drawn for a random lens: the barrel distortion of the small wide lenses
DAVIS cameras carry."""

_RANDOM_K2_OVER_K1_SQUARED = (0.5, 1.0)
"""Range of ``k2 / k1^2``: above 0.45 the radial curve ``r (1 + k1 r^2 + k2 r^4)`` rises at every
radius, so that no random lens folds the image over."""

_RANDOM_TANGENTIAL = 0.002
"""Largest ``|p1|``, ``|p2|`` drawn: a slightly decentred lens."""

_ROUND_TRIP_PX = 0.01
"""Largest distance a pixel may land from itself through the lens and back."""

_RANDOM_STREAM = 0x1E45
"""Mixed into the seed so that the lens draw leaves every other draw of the seed unchanged."""


def lens_distortion(lens: str, seed: int) -> tuple[float, ...]:
    """OpenCV's coefficients of a lens given as ``pinhole``, ``random`` or ``k1,k2,p1,p2[,k3]``.

    Raises:
        UsageError: the value is none of these.
    """
    if lens == "pinhole":
        return ()
    if lens == "random":
        rng = np.random.default_rng([seed, _RANDOM_STREAM])
        k1 = rng.uniform(*_RANDOM_K1)
        k2 = rng.uniform(*_RANDOM_K2_OVER_K1_SQUARED) * k1 * k1
        p1, p2 = rng.uniform(-_RANDOM_TANGENTIAL, _RANDOM_TANGENTIAL, 2)
        return tuple(float(value) for value in (k1, k2, p1, p2))
    try:
        values = tuple(float(word) for word in lens.split(","))
    except ValueError:
        values = ()
    if not 4 <= len(values) <= 5 or not all(np.isfinite(values)) or abs(values[0]) >= 1:
        raise UsageError(
            f"lens {lens!r}: give pinhole, random or OpenCV's k1,k2,p1,p2[,k3] (|k1| < 1)"
        )
    return values


class LensView:
    """Renders through ``lens`` from a pinhole render that covers all of its rays.

    Args:
        lens: the camera's lens (a pinhole renders directly).
    """

    def __init__(self, lens: Lens):
        self.lens = lens

    @cached_property
    def _maps(self) -> tuple[PinholeCamera, np.ndarray, np.ndarray]:
        lens = self.lens
        rays = lens.pixel_rays()
        columns = rays[..., 0] * lens.fx
        rows = rays[..., 1] * lens.fy
        left, top = np.floor(columns.min()) - 1, np.floor(rows.min()) - 1
        width = int(np.ceil(columns.max() - left)) + 2
        height = int(np.ceil(rows.max() - top)) + 2
        pixels = np.stack(np.meshgrid(np.arange(lens.width), np.arange(lens.height)), axis=-1)
        folded = np.abs(lens.project(rays.reshape(-1, 2)) - pixels.reshape(-1, 2)).max()
        if not folded < _ROUND_TRIP_PX:
            raise UsageError(
                f"lens {lens.summary()}: it folds the image over on itself (pixels map back "
                f"{folded:.2g} px away from where they came from); weaken k1 or strengthen k2"
            )
        cover = PinholeCamera(width, height, lens.fx, lens.fy, -left, -top)
        return cover, (columns - left).astype(np.float32), (rows - top).astype(np.float32)

    def render(self, scene, c2w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear HDR radiance ``(H, W, 3)`` float32 and optical-axis depth ``(H, W)`` of a pose.

        Args:
            scene: a :class:`~davis_io.emulator.scene.Scene`.
            c2w: camera-to-world ``4x4``, OpenCV axes.
        """
        if self.lens.is_pinhole:
            return scene.render(self.camera, c2w)
        cover, across, down = self._maps
        radiance, depth = scene.render(cover, c2w)
        seen = cv2.remap(radiance, across, down, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        far = cv2.remap(depth, across, down, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)
        return seen, far

    @cached_property
    def camera(self) -> PinholeCamera:
        """The lens's pinhole (its intrinsics without the distortion)."""
        lens = self.lens
        return PinholeCamera(lens.width, lens.height, lens.fx, lens.fy, lens.cx, lens.cy)
