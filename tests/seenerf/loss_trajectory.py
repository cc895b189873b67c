"""The loss terms of short fixed-seed fits, step by step: what a change to the training loop's
structure must leave as it was (``tests/fixtures/loss_trajectories.json``).

    python tests/seenerf/loss_trajectory.py   # writes the fixture from the code as it is
"""

import json
import sys
from pathlib import Path

import torch

from seenerf.data.synthetic import plane_scene
from seenerf.model.config import FitConfig
from seenerf.train.methods import make_method
from seenerf.train.trainer import Trainer

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "loss_trajectories.json"
FITS = {
    "full": {},
    "oracle": {"variant": "oracle"},
    "no-events": {"variant": "no-events"},
    "base": {"variant": "base"},
    "full, poses refined": {"refine_poses": True},
}
"""Each fit by name: its options beyond the common ones."""


def trajectory(options: dict) -> list[dict]:
    """Each step's loss terms of a 12-step fit of a small plane scene on one thread."""
    torch.set_num_threads(1)
    scene = plane_scene(height=12, width=16, frames=3, b=2, test_views=1)
    common = {"steps": 12, "batch_pixels": 16, "warm_steps": 3, "validation_share": 0.05}
    config = FitConfig.of(**common, threads=1, **options)
    terms = []

    def keep(trainer: Trainer) -> None:
        terms.append(dict(trainer.last_terms))

    Trainer(make_method(scene, config), log=lambda line: None, on_step=keep).train()
    return terms


if __name__ == "__main__":
    fits = {name: trajectory(options) for name, options in FITS.items()}
    FIXTURE.write_text(json.dumps(fits, indent=1) + "\n")
    sys.exit(0)
