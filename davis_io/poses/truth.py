"""Estimated poses against an emulated session's ground truth (evaluation only).

Estimated poses live in COLMAP's frame; a similarity fitted between the estimated and the
true training poses (Umeyama on camera centres and points along the camera axes) relates
the two. Everything here reads ``truth/`` and therefore only
exists for emulated sessions; nothing in the estimation itself uses it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from davis_io.geometry import Similarity, align_poses, interpolate_poses, rotation_error_deg
from davis_io.session import Session, SessionPoses

__all__ = ["PoseErrors", "compare_with_truth", "store_true_poses"]


@dataclass(frozen=True)
class PoseErrors:
    """Errors of registered latent poses after the similarity alignment to the truth.

    Attributes:
        rotation_deg: ``(N,)`` rotation error per registered latent pose, degrees.
        translation_fraction: ``(N,)`` centre error per registered latent pose, as a fraction
            of the scene's extent (truth attribute ``extent``).
        alignment: the fitted similarity, estimated frame to true frame.
    """

    rotation_deg: np.ndarray
    translation_fraction: np.ndarray
    alignment: Similarity

    @property
    def median_rotation_deg(self) -> float:
        """Median rotation error, degrees."""
        return float(np.median(self.rotation_deg))

    @property
    def median_translation_fraction(self) -> float:
        """Median centre error over the scene extent."""
        return float(np.median(self.translation_fraction))


def compare_with_truth(poses: SessionPoses, split_us: np.ndarray, truth) -> PoseErrors:
    """Align registered latent poses to the true poses at the same times and measure errors.

    Args:
        poses: estimated poses of a session.
        split_us: ``(F, b+1)`` latent time points, µs.
        truth: the session's :class:`~davis_io.emulator.Truth`.
    """
    registered = poses.registered.reshape(-1)
    estimated = poses.c2w.reshape(-1, 4, 4)[registered]
    true = truth.c2w_at(split_us.reshape(-1)[registered])
    alignment = align_poses(estimated, true)
    aligned = alignment.apply_poses(estimated)
    rotation = rotation_error_deg(aligned[:, :3, :3], true[:, :3, :3])
    distance = np.linalg.norm(aligned[:, :3, 3] - true[:, :3, 3], axis=1)
    return PoseErrors(rotation, distance / truth.extent, alignment)


def store_true_poses(session_dir: Path, b: int) -> None:
    """Store the truth's camera path as the session's poses for ``b`` bins per exposure.

    The true training poses (every sub-frame time of every exposure) are interpolated at the
    ``(F, b+1)`` latent time points and written with every pose marked registered, the truth's
    intrinsics and its lens's distortion, and depth bounds of the truth's depth range widened by
    10 % each way. Evaluation only: it lets a fit run on an emulated session without pose
    estimation.
    """
    from davis_io.emulator.lens_view import lens_distortion
    from davis_io.session.truth import load_truth

    with Session.open(session_dir) as session:
        truth = load_truth(session.truth_dir)
        split = session.bins(b).split_us
        times = truth.train_time_us.reshape(-1)
        order = np.argsort(times, kind="stable")
        keep = np.concatenate([[True], np.diff(times[order]) > 0])
        known = truth.train_c2w.reshape(-1, 4, 4)[order][keep]
        latent = interpolate_poses(times[order][keep], known, split.reshape(-1))
        near, far = truth.depth_range_m
        session.write_poses(
            b,
            SessionPoses(
                latent.reshape(*split.shape, 4, 4),
                np.ones(split.shape, bool),
                truth.intrinsics,
                np.asarray(lens_distortion(truth.camera.get("lens", "pinhole"), truth.seed), float),
                np.array([0.9 * near, 1.1 * far]),
            ),
        )
