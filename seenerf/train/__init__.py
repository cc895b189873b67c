"""Training a model on a session: the builder, the loop, losses, checkpoints, fits and runs."""

from seenerf.train.fit import fit_data
from seenerf.train.runs import evaluate_run, render_run
from seenerf.train.session_fit import fit_session

__all__ = ["evaluate_run", "fit_data", "fit_session", "render_run"]
