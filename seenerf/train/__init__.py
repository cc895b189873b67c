"""Training a model on a session: the builder, the loop, losses, checkpoints, fits and runs."""

from seenerf.train.fit import fit_data, fit_session
from seenerf.train.runs import evaluate_run, render_run

__all__ = ["evaluate_run", "fit_data", "fit_session", "render_run"]
