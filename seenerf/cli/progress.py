"""A fit's progress: a bar per training run on a terminal, a line every half minute in a log."""

from __future__ import annotations

import math
import sys
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the verbs import without torch
    from seenerf.train.trainer import TrainingProgress

__all__ = ["TrainingBar"]

LOG_EVERY_S = 30.0
"""Seconds between two progress lines when the output is not a terminal."""


def _describe(progress: TrainingProgress) -> str:
    rate = progress.steps / max(progress.elapsed_s, 1e-9)
    of_steps = f"/{progress.total_steps}" if math.isfinite(progress.total_steps) else ""
    of_time = f" of {progress.budget_s:.0f}" if math.isfinite(progress.budget_s) else ""
    return (
        f"step {progress.steps}{of_steps}, {progress.elapsed_s:.0f}{of_time} s, {rate:.1f} steps/s"
    )


class TrainingBar:
    """A tqdm bar over a fit's time budget (or its steps) on a terminal; else plain lines.

    Args:
        quiet: show nothing at all.
        label: what the bar (or line) is of: a session's name when several fit at once.
        position: the bar's row among several (None: the next free one).
    """

    def __init__(self, quiet: bool, label: str = "training", position: int | None = None):
        self.quiet, self.label, self.position = quiet, label, position
        self.terminal = sys.stderr.isatty()
        self.bar, self.logged_at = None, -math.inf

    def line(self, text: str) -> None:
        """Print a line above the bar (or alone before it exists)."""
        if self.quiet:
            return
        if self.bar is None:
            print(text, flush=True)
        else:
            self.bar.write(text)

    def update(self, progress: TrainingProgress) -> None:
        """Move the bar to ``progress`` (drawn at most twice a second; logged every 30 s)."""
        if self.quiet:
            return
        if not self.terminal:
            if time.monotonic() - self.logged_at >= LOG_EVERY_S:
                print(f"{self.label}: {_describe(progress)}", file=sys.stderr, flush=True)
                self.logged_at = time.monotonic()
            return
        by_time = math.isfinite(progress.budget_s)
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(
                total=max(round(progress.budget_s), 1) if by_time else progress.total_steps,
                unit="s" if by_time else "step",
                desc=self.label,
                position=self.position,
                dynamic_ncols=True,
                mininterval=0.5,
            )
        done = min(round(progress.elapsed_s), self.bar.total) if by_time else progress.steps
        rate = progress.steps / max(progress.elapsed_s, 1e-9)
        self.bar.set_postfix_str(f"step {progress.steps}, {rate:.1f} steps/s", refresh=False)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """Finish the bar (a later update starts a new one)."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None
