"""Pose geometry: similarity fits, pose errors, interpolation in time and frame conversions.

Rotations are handled by SciPy's ``Rotation`` and ``Slerp``; the similarity fit (Umeyama) is
our own, since neither SciPy nor pycolmap's Python API fits one with a scale to point pairs.

Every pose here is a camera-to-world ``4x4`` matrix with OpenCV camera axes (x right, y down,
z forward), the project's convention. COLMAP stores world-to-camera poses with the same camera
axes, so the conversion from COLMAP is a rigid inverse; this module is the only place that does
it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from davis_io.errors import UsageError

__all__ = [
    "Similarity",
    "align_poses",
    "c2w_from_w2c",
    "colmap_from_opencv_intrinsics",
    "opencv_from_colmap_intrinsics",
    "OPENCV_TO_OPENGL",
    "interpolate_poses",
    "nerfstudio_transforms",
    "mean_rotation",
    "rotation_error_deg",
    "umeyama",
]


@dataclass(frozen=True)
class Similarity:
    """A similarity transform ``x -> scale * rotation @ x + translation``.

    Attributes:
        scale: positive scale factor.
        rotation: ``(3, 3)`` rotation matrix (determinant +1).
        translation: ``(3,)`` translation, in the target frame's units.
    """

    scale: float
    rotation: np.ndarray
    translation: np.ndarray

    def apply_points(self, points: np.ndarray) -> np.ndarray:
        """Map ``(N, 3)`` points to the target frame."""
        return self.scale * np.asarray(points, float) @ self.rotation.T + self.translation

    def apply_poses(self, c2w: np.ndarray) -> np.ndarray:
        """Map ``(..., 4, 4)`` camera-to-world poses to the target frame."""
        c2w = np.asarray(c2w, float)
        out = c2w.copy()
        out[..., :3, :3] = self.rotation @ c2w[..., :3, :3]
        out[..., :3, 3] = self.apply_points(c2w[..., :3, 3])
        return out

    def inverse(self) -> Similarity:
        """The transform that maps the target frame back to the source frame."""
        rotation = self.rotation.T
        return Similarity(1.0 / self.scale, rotation, -(rotation @ self.translation) / self.scale)


def umeyama(source: np.ndarray, target: np.ndarray, *, with_scale: bool = True) -> Similarity:
    """Least-squares similarity mapping ``source`` points onto ``target`` points (Umeyama 1991).

    Minimises ``sum ||target_i - (s R source_i + t)||^2`` in closed form from the SVD of the
    cross-covariance, with the reflection correction that keeps ``det R = +1``.

    Args:
        source: ``(N, 3)`` points, e.g. estimated camera centres.
        target: ``(N, 3)`` corresponding points, e.g. true camera centres.
        with_scale: fit the scale too (``False`` gives the rigid fit, scale 1).

    Returns:
        The fitted :class:`Similarity`.

    Raises:
        UsageError: shapes differ, fewer than 3 points, or the source points are all equal.
    """
    source = np.asarray(source, float)
    target = np.asarray(target, float)
    if source.shape != target.shape or source.ndim != 2 or source.shape[1] != 3:
        raise UsageError(
            f"umeyama needs two (N, 3) point sets of equal shape, got {source.shape} and "
            f"{target.shape}"
        )
    if len(source) < 3:
        raise UsageError(f"umeyama needs at least 3 point pairs, got {len(source)}")
    source_mean, target_mean = source.mean(axis=0), target.mean(axis=0)
    source_centred, target_centred = source - source_mean, target - target_mean
    source_variance = np.mean(np.sum(source_centred**2, axis=1))
    if source_variance <= 1e-18:
        raise UsageError("umeyama: the source points all coincide; a similarity is undefined")
    covariance = target_centred.T @ source_centred / len(source)
    u, singular, vt = np.linalg.svd(covariance)
    sign = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        sign[2, 2] = -1.0
    rotation = u @ sign @ vt
    scale = float(np.trace(np.diag(singular) @ sign) / source_variance) if with_scale else 1.0
    translation = target_mean - scale * rotation @ source_mean
    return Similarity(scale, rotation, translation)


def mean_rotation(rotations: np.ndarray) -> np.ndarray:
    """The rotation closest (chordal L2) to ``(N, 3, 3)`` rotations: their mean, projected."""
    return Rotation.from_matrix(np.asarray(rotations, float)).mean().as_matrix()


def align_poses(source_c2w: np.ndarray, target_c2w: np.ndarray) -> Similarity:
    """Similarity mapping ``source`` poses onto ``target`` poses: orientations, then centres.

    The rotation is the one that best turns the source cameras' orientations into the target's
    (their chordal mean); scale and translation then fit the centres under that rotation. A
    structure-from-motion solution of a forward-facing hand-held sweep pins every camera's
    orientation tightly but leaves the plane of the camera centres free to tilt by a fraction
    of a degree against them (a view at a new position must keep its orientation to the scene);
    a rotation fitted to the centres takes that tilt into every mapped orientation. On the
    emulator's scenes, from perfect sharp images at the true poses, COLMAP's centres tilt
    0.43 degrees against its orientations: 2 px at 280 px focal length.

    Args:
        source_c2w: ``(N, 4, 4)`` poses, e.g. estimated.
        target_c2w: ``(N, 4, 4)`` corresponding poses, e.g. true.

    Raises:
        UsageError: fewer than 2 poses, or the source centres all coincide.
    """
    source_c2w, target_c2w = np.asarray(source_c2w, float), np.asarray(target_c2w, float)
    if source_c2w.shape != target_c2w.shape or len(source_c2w) < 2:
        raise UsageError(
            f"align_poses needs two equal stacks of at least 2 poses, got {source_c2w.shape} "
            f"and {target_c2w.shape}"
        )
    rotation = mean_rotation(target_c2w[:, :3, :3] @ np.swapaxes(source_c2w[:, :3, :3], 1, 2))
    source = source_c2w[:, :3, 3] @ rotation.T
    target = target_c2w[:, :3, 3]
    source_centred = source - source.mean(axis=0)
    spread = float(np.sum(source_centred**2))
    if spread <= 1e-18:
        raise UsageError("align_poses: the source centres all coincide; a scale is undefined")
    scale = float(np.sum(source_centred * (target - target.mean(axis=0))) / spread)
    return Similarity(scale, rotation, target.mean(axis=0) - scale * source.mean(axis=0))


def rotation_error_deg(rotation_a: np.ndarray, rotation_b: np.ndarray) -> np.ndarray:
    """Angle of ``R_a^T R_b`` in degrees, for ``(..., 3, 3)`` stacks of rotations."""
    relative = np.swapaxes(np.asarray(rotation_a, float), -1, -2) @ np.asarray(rotation_b, float)
    cosine = (np.trace(relative, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def c2w_from_w2c(rotation_w2c: np.ndarray, translation_w2c: np.ndarray) -> np.ndarray:
    """Camera-to-world ``4x4`` from COLMAP's world-to-camera ``R, t`` (same OpenCV camera axes).

    ``x_cam = R x_world + t``, so ``c2w = [[R^T, -R^T t], [0, 1]]``.
    """
    rotation = np.asarray(rotation_w2c, float)
    c2w = np.eye(4)
    c2w[:3, :3] = rotation.T
    c2w[:3, 3] = -rotation.T @ np.asarray(translation_w2c, float)
    return c2w


COLMAP_PIXEL_OFFSET = 0.5
"""COLMAP puts the centre of the top-left pixel at (0.5, 0.5); OpenCV and the session at (0, 0)."""


def opencv_from_colmap_intrinsics(intrinsics: np.ndarray) -> np.ndarray:
    """``(fx, fy, cx, cy)`` from COLMAP's pixel convention to the session's (OpenCV)."""
    out = np.array(intrinsics, float)
    out[2:] -= COLMAP_PIXEL_OFFSET
    return out


def colmap_from_opencv_intrinsics(intrinsics: np.ndarray) -> np.ndarray:
    """``(fx, fy, cx, cy)`` from the session's pixel convention (OpenCV) to COLMAP's."""
    out = np.array(intrinsics, float)
    out[2:] += COLMAP_PIXEL_OFFSET
    return out


def interpolate_poses(
    known_times_us: np.ndarray, known_c2w: np.ndarray, query_times_us: np.ndarray
) -> np.ndarray:
    """Camera-to-world poses at ``query_times_us`` from poses known at other times.

    Rotations are slerped and centres interpolated linearly between the two nearest known
    times; outside the known range the nearest known pose is held (no extrapolation).

    Args:
        known_times_us: ``(K,)`` strictly increasing times, µs.
        known_c2w: ``(K, 4, 4)`` poses at those times.
        query_times_us: ``(Q,)`` times, µs (any order).

    Returns:
        ``(Q, 4, 4)`` poses.

    Raises:
        UsageError: no known pose, mismatched lengths or times not strictly increasing.
    """
    times = np.asarray(known_times_us, np.int64)
    known_c2w = np.asarray(known_c2w, float)
    if len(times) == 0 or len(times) != len(known_c2w):
        raise UsageError(
            f"interpolate_poses needs at least one known pose and one time per pose, got "
            f"{len(times)} times and {len(known_c2w)} poses"
        )
    if np.any(np.diff(times) <= 0):
        raise UsageError("interpolate_poses: known times must be strictly increasing")
    query = np.asarray(query_times_us, np.int64)
    if len(times) == 1:
        return np.repeat(known_c2w[:1], len(query), axis=0)
    rotations = Slerp(times, Rotation.from_matrix(known_c2w[:, :3, :3]))
    clamped = np.clip(query, times[0], times[-1])
    upper = np.clip(np.searchsorted(times, clamped), 1, len(times) - 1)
    lower = upper - 1
    fractions = (clamped - times[lower]) / (times[upper] - times[lower])
    out = np.tile(np.eye(4), (len(query), 1, 1))
    out[:, :3, :3] = rotations(clamped).as_matrix()
    out[:, :3, 3] = (1 - fractions)[:, None] * known_c2w[lower, :3, 3] + fractions[
        :, None
    ] * known_c2w[upper, :3, 3]
    return out


OPENCV_TO_OPENGL = np.diag([1.0, -1.0, -1.0, 1.0])
"""Right-multiply an OpenCV camera-to-world (x right, y down, z forward) to get OpenGL axes (x
right, y up, z backward), the convention of nerfstudio's and instant-ngp's ``transforms.json``."""

NERFSTUDIO_PIXEL_OFFSET = 0.5
"""nerfstudio and instant-ngp put pixel ``i``'s centre at ``i + 0.5``; the session at ``i``."""


def nerfstudio_transforms(
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    distortion: np.ndarray,
    image_size: tuple[int, int],
    file_paths: list[str],
) -> dict:
    """A ``transforms.json`` that nerfstudio's and instant-ngp's loaders read.

    Camera-to-world in OpenGL axes, the principal point moved to their pixel convention (pixel
    centres at +0.5), the OpenCV model with its distortion keys (k1, k2, p1, p2, and k3 when the
    lens has one; zero when the session has none).

    Args:
        c2w: ``(N, 4, 4)`` OpenCV camera-to-world.
        intrinsics: ``(fx, fy, cx, cy)``, pixel centres at integers.
        distortion: OpenCV coefficients ``k1, k2, p1, p2, ...`` (may be empty).
        image_size: ``(height, width)``.
        file_paths: each view's image, relative to the JSON file.
    """
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    coefficients = np.zeros(5)
    known = np.asarray(distortion, float).ravel()[:5]
    coefficients[: len(known)] = known
    frames = [
        {"file_path": name, "transform_matrix": (pose @ OPENCV_TO_OPENGL).tolist()}
        for name, pose in zip(file_paths, np.asarray(c2w, float), strict=True)
    ]
    k1, k2, p1, p2, k3 = (float(c) for c in coefficients)
    return {
        "camera_model": "OPENCV",
        "fl_x": fx,
        "fl_y": fy,
        "cx": cx + NERFSTUDIO_PIXEL_OFFSET,
        "cy": cy + NERFSTUDIO_PIXEL_OFFSET,
        "w": int(image_size[1]),
        "h": int(image_size[0]),
        "k1": k1,
        "k2": k2,
        "p1": p1,
        "p2": p2,
        **({"k3": k3} if k3 else {}),
        "frames": frames,
    }
