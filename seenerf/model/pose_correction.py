"""A small rigid correction of each training view's poses, learned with the field.

The poses of a recording come from COLMAP on EDI latent frames: good to a fraction of a degree
where the calibration was, worse where it was not. Each training view gets a rotation (axis
times angle, radians) and a translation (scene units) in its own camera's frame, applied to
every latent pose of its exposure (``c2w @ correction``), starting at none. A quadratic prior
keeps them small, so that the field, not the cameras, explains what the frames show; the test
poses are mapped from the corrected training cameras as from the estimated ones.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

__all__ = ["LEARNING_RATE", "PRIOR_WEIGHT", "PoseCorrection", "rotation_matrices"]

PRIOR_WEIGHT = 1e-2
"""Weight of the mean squared correction (radians², scene units²) in the loss."""

LEARNING_RATE = 3e-4
"""Adam's rate of the corrections, before the schedule's fall: a few hundredths of a degree per
step at most, about what a step of the field moves an edge."""


def rotation_matrices(axis_angle: torch.Tensor) -> torch.Tensor:
    """``(N, 3, 3)`` rotations of ``(N, 3)`` axis-angle vectors (Rodrigues' formula).

    The coefficients use their series near zero angle, where the closed forms divide 0 by 0.
    """
    theta2 = (axis_angle**2).sum(-1, keepdim=True)[..., None]
    small = theta2 < 1e-8
    theta = torch.sqrt(torch.where(small, torch.ones_like(theta2), theta2))
    sin_over = torch.where(small, 1 - theta2 / 6, torch.sin(theta) / theta)
    cos_over = torch.where(small, 0.5 - theta2 / 24, (1 - torch.cos(theta)) / theta**2)
    x, y, z = axis_angle.unbind(-1)
    zero = torch.zeros_like(x)
    skew = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], -1).reshape(-1, 3, 3)
    eye = torch.eye(3, dtype=axis_angle.dtype, device=axis_angle.device)
    return eye + sin_over * skew + cos_over * (skew @ skew)


class PoseCorrection(nn.Module):
    """One learned rigid correction per training view, applied in the camera's frame.

    Args:
        views: number of training views (frames).
    """

    def __init__(self, views: int):
        super().__init__()
        self.twist = nn.Parameter(torch.zeros(views, 6))

    def matrices(self, view: torch.Tensor | None = None) -> torch.Tensor:
        """``(N, 4, 4)`` corrections of the given views (all when None)."""
        twist = self.twist if view is None else self.twist[view]
        correction = torch.zeros(len(twist), 4, 4, dtype=twist.dtype, device=twist.device)
        correction[:, :3, :3] = rotation_matrices(twist[:, :3])
        correction[:, :3, 3] = twist[:, 3:]
        correction[:, 3, 3] = 1.0
        return correction

    def forward(self, c2w: torch.Tensor, view: torch.Tensor) -> torch.Tensor:
        """``(N, P, 4, 4)`` poses of views ``view`` ``(N,)``, each corrected."""
        return c2w @ self.matrices(view)[:, None].to(c2w.dtype)

    def prior(self) -> torch.Tensor:
        """Mean squared correction over the views: zero when none."""
        return (self.twist**2).sum(-1).mean()

    @torch.no_grad()
    def apply(self, c2w: np.ndarray) -> np.ndarray:
        """``(F, P, 4, 4)`` poses of every view, corrected."""
        poses = torch.as_tensor(c2w, dtype=torch.float32, device=self.twist.device)
        return self.forward(poses, torch.arange(len(poses))).cpu().numpy().astype(c2w.dtype)

    @torch.no_grad()
    def sizes(self) -> tuple[np.ndarray, np.ndarray]:
        """Each view's correction: rotation in degrees and translation in scene units."""
        twist = self.twist.detach().cpu().numpy().astype(np.float64)
        turned = np.degrees(np.linalg.norm(twist[:, :3], axis=1))
        return turned, np.linalg.norm(twist[:, 3:], axis=1)
