"""LPIPS, only when its network and weights are already on this machine: never downloaded.

LPIPS (Zhang et al. 2018) compares deep features of a pretrained AlexNet; the ``lpips`` package
holds its calibrated linear layers and takes AlexNet's ImageNet weights from torchvision, which
fetches them from the internet unless the torch hub cache already has them. A fit must not reach
the network, so the score is computed only when the package is installed and the weights are in
that cache; otherwise the metrics say why it is missing.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

__all__ = ["ALEXNET_WEIGHTS", "lpips_scorer"]

ALEXNET_WEIGHTS = "alexnet-owt-7be5be79.pth"
"""torchvision's file name of AlexNet's ImageNet weights in the torch hub cache."""

Scorer = Callable[[np.ndarray, np.ndarray], float]


def lpips_scorer(hub_dir: Path | None = None) -> tuple[Scorer | None, str]:
    """An LPIPS scorer of ``(H, W, C)`` images in [0, 1], or None and the reason it is missing.

    Args:
        hub_dir: the torch hub folder (default ``torch.hub.get_dir()``).
    """
    if importlib.util.find_spec("lpips") is None:
        return None, "LPIPS not computed: the lpips package is not installed"
    weights = Path(hub_dir or torch.hub.get_dir()) / "checkpoints" / ALEXNET_WEIGHTS
    if not weights.exists():
        return None, f"LPIPS not computed: AlexNet weights are not in {weights.parent}"
    import lpips

    network = lpips.LPIPS(net="alex", verbose=False).eval()

    @torch.no_grad()
    def score(predicted: np.ndarray, truth: np.ndarray) -> float:
        def tensor(image: np.ndarray) -> torch.Tensor:
            image = np.clip(np.asarray(image, np.float32), 0.0, 1.0)
            image = np.repeat(image, 3, axis=-1) if image.shape[-1] == 1 else image
            return torch.as_tensor(image).permute(2, 0, 1)[None] * 2.0 - 1.0

        return float(network(tensor(predicted), tensor(truth)))

    return score, "LPIPS (AlexNet, lpips package, local weights)"
