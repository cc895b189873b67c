"""The frame a fit lives in: the similarity that maps the truth's poses into it."""

from __future__ import annotations

import numpy as np

from davis_io.geometry import Similarity, align_poses
from seenerf.data.arrays import TrainingData

__all__ = ["IDENTITY", "test_poses_in_fit_frame", "truth_to_fit_frame"]

IDENTITY = Similarity(1.0, np.eye(3), np.zeros(3))
"""The similarity of a fit trained in the truth frame (the oracle)."""


def truth_to_fit_frame(data: TrainingData) -> Similarity:
    """Similarity from the truth frame to the fit's (estimated) frame, from centres and axes.

    Aligns the estimated latent poses to the true poses at the same instants (camera centres
    and orientations, :func:`~davis_io.geometry.align_poses`) and inverts the result.
    Without truth, or with fewer than three distinct centres, the frames are taken to coincide.
    """
    if data.truth is None or data.truth.latent_c2w is None:
        return IDENTITY
    estimated = data.c2w.reshape(-1, 4, 4).astype(np.float64)
    true = data.truth.latent_c2w.reshape(-1, 4, 4).astype(np.float64)
    if len(estimated) < 3 or np.allclose(estimated[:, :3, 3], estimated[0, :3, 3]):
        return IDENTITY
    return align_poses(estimated, true).inverse()


def test_poses_in_fit_frame(
    data: TrainingData, trained_in_truth_frame: bool
) -> tuple[np.ndarray, Similarity]:
    """Test poses mapped into the fit's frame, or each frame's first latent pose without truth."""
    if data.test is None:
        return data.c2w[:, 0], IDENTITY
    similarity = IDENTITY if trained_in_truth_frame else truth_to_fit_frame(data)
    return similarity.apply_poses(data.test.c2w).astype(np.float32), similarity
