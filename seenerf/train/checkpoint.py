"""Checkpoints of a training run: written atomically, read back with ``weights_only=True``."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import torch

from seenerf.errors import CheckpointError

__all__ = ["load_checkpoint", "load_model_state", "save_checkpoint"]


def save_checkpoint(path: Path, trainer) -> None:
    """Write model, optimiser, occupancy grid, random state and progress of ``trainer``."""
    grid = trainer.model.renderer.grid
    summary = trainer.summary
    state = {
        "key": json.dumps(trainer.config.training_key(), sort_keys=True),
        "model": trainer.model.state_dict(),
        "optimizer": trainer.optimizer.state_dict(),
        "grid_density": grid.density if grid is not None else torch.zeros(0),
        "generator": trainer.generator.get_state(),
        "steps": summary.steps,
        "elapsed_s": summary.elapsed_s,
        "best_psnr": summary.best_psnr,
        "evals_since_best": trainer.evals_since_best,
        "history": json.dumps(summary.history),
    }
    temporary = path.with_suffix(".tmp")
    try:
        torch.save(state, temporary)
        os.replace(temporary, path)
    except (OSError, RuntimeError) as error:  # torch reports a full disk as a RuntimeError
        temporary.unlink(missing_ok=True)
        free_mb = shutil.disk_usage(path.parent).free / 1e6
        kept = "the previous checkpoint is kept" if path.exists() else "no checkpoint was kept"
        raise CheckpointError(
            f"cannot write the checkpoint {path} ({free_mb:.0f} MB free on its disk: "
            f"{str(error).splitlines()[0]}); {kept}: free some space and run the fit again to "
            "resume"
        ) from error


def _read(path: Path) -> dict:
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many types for a damaged or foreign file
        raise CheckpointError(
            f"{path}: not a readable seecap checkpoint ({type(error).__name__}: {error}); "
            "delete it or run with --fresh"
        ) from error


def _load_weights(path: Path, model, weights: dict) -> None:
    try:
        model.load_state_dict(weights)
    except RuntimeError as error:  # parameters missing, unexpected or of another shape
        raise CheckpointError(
            f"{path}: its weights do not fit this version's model ({error}); refit with --fresh"
        ) from error


def load_checkpoint(path: Path, trainer) -> None:
    """Restore ``trainer`` from ``path``.

    Raises:
        CheckpointError: unreadable file, or written by a fit with another configuration.
    """
    state = _read(path)
    if state.get("key") != json.dumps(trainer.config.training_key(), sort_keys=True):
        raise CheckpointError(
            f"{path} was written by a fit with another configuration; run with --fresh to start "
            "over or choose another --run name"
        )
    _load_weights(path, trainer.model, state["model"])
    trainer.optimizer.load_state_dict(state["optimizer"])
    grid = trainer.model.renderer.grid
    if grid is not None and state["grid_density"].numel():
        grid.set_density(state["grid_density"])
    trainer.generator.set_state(state["generator"])
    summary = trainer.summary
    summary.steps, summary.elapsed_s = int(state["steps"]), float(state["elapsed_s"])
    summary.best_psnr = float(state["best_psnr"])
    summary.history = json.loads(state["history"])
    trainer.evals_since_best = int(state["evals_since_best"])


def load_model_state(path: Path, model) -> None:
    """Load only the model weights (and occupancy grid) of a checkpoint, for rendering.

    Raises:
        CheckpointError: unreadable file, or weights of another model.
    """
    state = _read(path)
    _load_weights(path, model, state["model"])
    grid = model.renderer.grid
    if grid is not None and state["grid_density"].numel():
        grid.set_density(state["grid_density"])
