"""Tiny ray-cast scenes with known poses for the pose tests: a textured box seen from inside."""

from __future__ import annotations

import cv2
import numpy as np

WIDTH, HEIGHT = 346, 260
FOCAL = 260.0
INTRINSICS = np.array([FOCAL, FOCAL, WIDTH / 2, HEIGHT / 2])
BOX_HALF_SIZE = 2.0  # the room spans [-2, 2]^3 metres


def texture(seed: int, size: int = 512) -> np.ndarray:
    """Multi-scale random texture in [0.05, 0.95] (float32), seeded."""
    rng = np.random.default_rng(seed)
    out = np.zeros((size, size), np.float32)
    for cells, gain in ((8, 1.0), (32, 0.7), (128, 0.5)):
        noise = rng.random((cells, cells)).astype(np.float32)
        out += gain * cv2.resize(noise, (size, size), interpolation=cv2.INTER_CUBIC)
    out -= out.min()
    return 0.05 + 0.9 * out / out.max()


def look_at(centre: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Camera-to-world pose (OpenCV axes) at ``centre`` looking at ``target``, y roughly down."""
    forward = (target - centre) / np.linalg.norm(target - centre)
    right = np.cross(forward, [0.0, -1.0, 0.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    c2w = np.eye(4)
    c2w[:3, :3] = np.stack([right, down, forward], axis=1)
    c2w[:3, 3] = centre
    return c2w


def render_box(c2w: np.ndarray, textures: list[np.ndarray], flat: bool = False) -> np.ndarray:
    """Render the inside of the textured box at ``c2w``; ``flat`` gives a textureless grey room."""
    columns, rows = np.meshgrid(np.arange(WIDTH) + 0.5, np.arange(HEIGHT) + 0.5)
    rays = (
        np.stack(
            [(columns - INTRINSICS[2]) / FOCAL, (rows - INTRINSICS[3]) / FOCAL, np.ones_like(rows)],
            axis=-1,
        )
        @ c2w[:3, :3].T
    )
    origin = c2w[:3, 3]
    image = np.zeros((HEIGHT, WIDTH), np.float32)
    nearest = np.full((HEIGHT, WIDTH), np.inf)
    for axis in range(3):
        for side, sign in enumerate((-1.0, 1.0)):
            with np.errstate(divide="ignore", invalid="ignore"):
                depth = (sign * BOX_HALF_SIZE - origin[axis]) / rays[..., axis]
            hit = (depth > 0) & (depth < nearest)
            point = origin + depth[..., None] * rays
            u_axis, v_axis = [a for a in range(3) if a != axis]
            tex = textures[2 * axis + side]
            scale = (tex.shape[0] - 1) / (2 * BOX_HALF_SIZE)
            map_x = ((point[..., u_axis] + BOX_HALF_SIZE) * scale).astype(np.float32)
            map_y = ((point[..., v_axis] + BOX_HALF_SIZE) * scale).astype(np.float32)
            sampled = cv2.remap(tex, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            image = np.where(hit, 0.5 if flat else sampled, image)
            nearest = np.where(hit, depth, nearest)
    return image


def orbit_poses(count: int, seed: int = 0) -> np.ndarray:
    """``count`` poses on a shaky arc near the room centre, looking at one wall region."""
    rng = np.random.default_rng(seed)
    poses = []
    for i in range(count):
        angle = -0.5 + i / max(count - 1, 1)
        centre = np.array([0.8 * np.sin(angle), 0.1 * np.cos(3 * angle), -0.6 + 0.2 * angle])
        target = np.array([1.2, 1.0, BOX_HALF_SIZE]) + 0.05 * rng.standard_normal(3)
        poses.append(look_at(centre + 0.01 * rng.standard_normal(3), target))
    return np.array(poses)
