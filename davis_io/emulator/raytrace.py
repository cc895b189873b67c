"""Vectorised ray casting of one-sided quads and spheres through a pinhole camera (numpy only).

World units are metres. Cameras use OpenCV axes (x right, y down, z forward) with pixel centres at
integer coordinates, so the ray of pixel ``(x, y)`` has camera-frame direction
``((x - cx) / fx, (y - cy) / fy, 1)`` and the distance along it is the depth on the optical axis.
Each surface is tested only against the pixels of its projected bounding rectangle, which keeps a
346x260 view of a furnished room at a few milliseconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from davis_io.errors import UsageError

__all__ = ["PinholeCamera", "Quad", "Sphere", "Surface", "Rect", "box_faces", "nearest_hits"]

Rect = tuple[int, int, int, int]
"""Pixel rectangle ``(y0, y1, x0, x1)``, ends excluded."""

_NEAR_M = 1e-3
_EPSILON = 1e-5


@dataclass(frozen=True)
class PinholeCamera:
    """An ideal pinhole camera without distortion.

    Attributes:
        width: image columns.
        height: image rows.
        fx: horizontal focal length in pixels.
        fy: vertical focal length in pixels.
        cx: principal point column in pixels (pixel centres are integers).
        cy: principal point row in pixels.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0 or self.fx <= 0 or self.fy <= 0:
            raise UsageError(
                f"camera {self.width}x{self.height} with focal {self.fx}, {self.fy} px: "
                "size and focal lengths must be positive"
            )

    @property
    def intrinsics(self) -> np.ndarray:
        """``(4,)`` float64 fx, fy, cx, cy in pixels."""
        return np.array([self.fx, self.fy, self.cx, self.cy], np.float64)

    @cached_property
    def across(self) -> np.ndarray:
        """``(W,)`` float32 x / z of each pixel column's rays, camera frame."""
        return ((np.arange(self.width) - self.cx) / self.fx).astype(np.float32)

    @cached_property
    def down(self) -> np.ndarray:
        """``(H,)`` float32 y / z of each pixel row's rays, camera frame."""
        return ((np.arange(self.height) - self.cy) / self.fy).astype(np.float32)

    def pixel_rect(self, points_camera: np.ndarray) -> Rect | None:
        """Pixel rectangle ``(y0, y1, x0, x1)`` (ends excluded) covering camera-frame points.

        Points must all lie in front of the camera; returns None when the rectangle misses the
        image.
        """
        x = points_camera[:, 0] / points_camera[:, 2] * self.fx + self.cx
        y = points_camera[:, 1] / points_camera[:, 2] * self.fy + self.cy
        x0, x1 = max(int(np.floor(x.min())), 0), min(int(np.ceil(x.max())) + 1, self.width)
        y0, y1 = max(int(np.floor(y.min())), 0), min(int(np.ceil(y.max())) + 1, self.height)
        return (y0, y1, x0, x1) if x0 < x1 and y0 < y1 else None


def _clip_near(polygon: np.ndarray) -> np.ndarray:
    """The part of a convex camera-frame polygon ``(K, 3)`` with z >= the near plane."""
    kept = []
    for index, point in enumerate(polygon):
        following = polygon[(index + 1) % len(polygon)]
        if point[2] >= _NEAR_M:
            kept.append(point)
        if (point[2] >= _NEAR_M) != (following[2] >= _NEAR_M):
            fraction = (_NEAR_M - point[2]) / (following[2] - point[2])
            kept.append(point + fraction * (following - point))
    return np.array(kept).reshape(-1, 3)


@dataclass(frozen=True)
class Quad:
    """A one-sided rectangle, visible from the side its normal ``u x v`` points to.

    Surface coordinates ``(s, r)`` are signed distances in metres from the centre along ``u``
    and ``v`` (unit, orthogonal axes); ``|s| <= half_u``, ``|r| <= half_v``.
    """

    center: tuple[float, float, float]
    u: tuple[float, float, float]
    v: tuple[float, float, float]
    half_u: float
    half_v: float
    axes: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        u, v = np.asarray(self.u, np.float64), np.asarray(self.v, np.float64)
        object.__setattr__(self, "axes", np.stack([u, v, np.cross(u, v)]))

    @property
    def normal(self) -> np.ndarray:
        """Unit front normal ``u x v``."""
        return self.axes[2]

    @property
    def uv_bounds(self) -> tuple[float, float, float, float]:
        """``(s_min, s_max, r_min, r_max)`` of the surface coordinates."""
        return (-self.half_u, self.half_u, -self.half_v, self.half_v)

    def points_at(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points ``(M, 3)`` and front normals ``(M, 3)`` at surface coordinates."""
        points = np.asarray(self.center) + np.einsum("mk,kc->mc", uv, self.axes[:2])
        return points, np.broadcast_to(self.normal, points.shape)

    def pixel_rect(self, camera: PinholeCamera, w2c: np.ndarray) -> Rect | None:
        """Pixel rectangle that can see the front of the quad, or None."""
        center = np.asarray(self.center)
        if (w2c[:3, :3].T @ -w2c[:3, 3] - center) @ self.normal <= 0:
            return None
        signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * [self.half_u, self.half_v]
        corners = (center + signs @ self.axes[:2]) @ w2c[:3, :3].T + w2c[:3, 3]
        clipped = _clip_near(corners)
        return camera.pixel_rect(clipped) if len(clipped) else None

    def trace(
        self, origin: np.ndarray, rotation: np.ndarray, across: np.ndarray, down: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Hits of the rays ``rotation @ (across[j], down[i], 1)`` from ``origin``.

        Args:
            origin: camera centre, world frame.
            rotation: camera-to-world rotation.
            across: ``(w,)`` x / z of the block's pixel columns (camera frame).
            down: ``(h,)`` y / z of the block's pixel rows.

        Returns:
            ``t`` ``(h, w)`` ray parameter (the optical-axis depth; ``inf`` where missed) and the
            surface coordinates ``s``, ``r`` ``(h, w)`` of the hits.
        """
        axes = (self.axes @ rotation).astype(np.float32)  # the axes in camera coordinates
        start = (self.axes @ (origin - np.asarray(self.center))).astype(np.float32)
        along = [(down[:, None] * axes[k, 1] + axes[k, 2]) + across * axes[k, 0] for k in range(3)]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -start[2] / along[2]
        s = start[0] + t * along[0]
        r = start[1] + t * along[1]
        hit = (np.abs(s) <= self.half_u) & (np.abs(r) <= self.half_v) & (t > _EPSILON)
        return np.where(hit, t, np.float32(np.inf)), s, r


@dataclass(frozen=True)
class Sphere:
    """A sphere seen from outside; surface coordinates are longitude and latitude arcs (m)."""

    center: tuple[float, float, float]
    radius: float

    @property
    def uv_bounds(self) -> tuple[float, float, float, float]:
        """``(s_min, s_max, r_min, r_max)`` of the surface coordinates."""
        return (
            -np.pi * self.radius,
            np.pi * self.radius,
            -np.pi / 2 * self.radius,
            np.pi / 2 * self.radius,
        )

    def points_at(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points and outward normals at surface coordinates."""
        longitude, latitude = uv[:, 0] / self.radius, uv[:, 1] / self.radius
        normal = np.stack(
            [
                np.cos(latitude) * np.sin(longitude),
                np.sin(latitude),
                np.cos(latitude) * np.cos(longitude),
            ],
            1,
        )
        return np.asarray(self.center) + self.radius * normal, normal

    def coordinates(self, offsets: np.ndarray) -> np.ndarray:
        """Surface coordinates of points given as offsets from the centre."""
        normal = offsets / np.float32(self.radius)
        longitude = np.arctan2(normal[:, 0], normal[:, 2])
        latitude = np.arcsin(np.clip(normal[:, 1], -1, 1))
        return np.stack([longitude, latitude], 1) * np.float32(self.radius)

    def pixel_rect(self, camera: PinholeCamera, w2c: np.ndarray) -> Rect | None:
        """Pixel rectangle covering the sphere's bounding cube, or None."""
        cube = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
        corners = (np.asarray(self.center) + self.radius * cube) @ w2c[:3, :3].T + w2c[:3, 3]
        if corners[:, 2].min() < _NEAR_M:
            centre_depth = (np.asarray(self.center) @ w2c[:3, :3].T + w2c[:3, 3])[2]
            visible = centre_depth > -self.radius
            return (0, camera.height, 0, camera.width) if visible else None
        return camera.pixel_rect(corners)

    def trace(
        self, origin: np.ndarray, rotation: np.ndarray, across: np.ndarray, down: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Hits of a block of rays, as :meth:`Quad.trace` (coordinates computed at hits only)."""
        offset = ((origin - np.asarray(self.center)) @ rotation).astype(np.float32)
        length2 = (down[:, None] ** 2 + 1) + across**2
        half_b = (down[:, None] * offset[1] + offset[2]) + across * offset[0]
        disc = half_b * half_b - length2 * np.float32(offset @ offset - self.radius**2)
        root = np.sqrt(np.maximum(disc, 0))
        near, far = (-half_b - root) / length2, (-half_b + root) / length2
        t = np.where(near > _EPSILON, near, far)
        t = np.where((disc >= 0) & (t > _EPSILON), t, np.float32(np.inf))
        s, r = np.zeros_like(t), np.zeros_like(t)
        rows, cols = np.nonzero(np.isfinite(t))
        if len(rows):
            hit_t = t[rows, cols]
            local = offset + hit_t[:, None] * np.stack(
                [across[cols], down[rows], np.ones_like(hit_t)], 1
            )
            s[rows, cols], r[rows, cols] = self.coordinates(local @ rotation.T.astype(np.float32)).T
        return t, s, r


Surface = Quad | Sphere


def box_faces(low: Sequence[float], high: Sequence[float], *, inward: bool = False) -> list[Quad]:
    """The six faces of an axis-aligned box, in the order -x, +x, -y, +y, -z, +z.

    Args:
        low: minimum corner, metres.
        high: maximum corner, metres.
        inward: normals point into the box (the walls of a room seen from inside).
    """
    low_a, high_a = np.asarray(low, float), np.asarray(high, float)
    if np.any(high_a <= low_a):
        raise UsageError(f"box corners {low} .. {high}: every high coordinate must exceed low")
    center, half = (low_a + high_a) / 2, (high_a - low_a) / 2
    faces = []
    for axis in range(3):
        a, b = [k for k in range(3) if k != axis]
        for sign in (-1.0, 1.0):
            u, v = np.eye(3)[a], np.eye(3)[b]
            outward = np.cross(u, v)[axis] * sign > 0
            if outward == inward:
                u, v, a, b = v, u, b, a
            face_center = center.copy()
            face_center[axis] += sign * half[axis]
            faces.append(Quad(tuple(face_center), tuple(u), tuple(v), half[a], half[b]))
    return faces


def nearest_hits(
    surfaces: Sequence[Surface], camera: PinholeCamera, c2w: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nearest surface along every pixel's ray, its depth and surface coordinates.

    Args:
        surfaces: quads and spheres.
        camera: pinhole intrinsics.
        c2w: ``(4, 4)`` camera-to-world, OpenCV axes.

    Returns:
        ``index`` ``(H, W)`` int16 of the surface hit (-1 where none), ``depth`` ``(H, W)``
        float32 along the optical axis (``inf`` where none) and ``uv`` ``(2, H, W)`` float32
        surface coordinates of the hits.
    """
    if len(surfaces) > np.iinfo(np.int16).max:
        raise UsageError(
            f"{len(surfaces)} surfaces; at most {np.iinfo(np.int16).max} are supported"
        )
    pose = np.asarray(c2w, np.float64)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise UsageError(f"c2w has shape {pose.shape}; give one finite 4x4 camera-to-world")
    w2c = np.linalg.inv(pose)
    rotation, origin = pose[:3, :3], pose[:3, 3]
    across, down = camera.across, camera.down
    depth = np.full((camera.height, camera.width), np.inf, np.float32)
    index = np.full((camera.height, camera.width), -1, np.int16)
    uv = np.zeros((2, camera.height, camera.width), np.float32)
    for number, surface in enumerate(surfaces):
        rect = surface.pixel_rect(camera, w2c)
        if rect is None:
            continue
        y0, y1, x0, x1 = rect
        t, s, r = surface.trace(origin, rotation, across[x0:x1], down[y0:y1])
        closer = t < depth[y0:y1, x0:x1]
        np.copyto(depth[y0:y1, x0:x1], t, where=closer)
        np.copyto(index[y0:y1, x0:x1], number, where=closer)
        np.copyto(uv[0, y0:y1, x0:x1], s, where=closer)
        np.copyto(uv[1, y0:y1, x0:x1], r, where=closer)
    return index, depth, uv
