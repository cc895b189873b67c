"""Typed errors of the See-NeRF trainer; each message says what was wrong, where, and what to do."""

from __future__ import annotations

from davis_io import SeecapError

__all__ = [
    "CheckpointError",
    "ConfigError",
    "OptionError",
    "SeeNerfError",
    "TrainingDataError",
    "TrainingStopped",
]


class SeeNerfError(SeecapError):
    """Base of every error raised on purpose by ``seenerf`` (caught by the ``seecap`` CLI)."""


class ConfigError(SeeNerfError):
    """A configuration cannot be used here (no CUDA, no truth for the oracle, no Ray)."""


class OptionError(ConfigError):
    """An option's value is unknown or out of range: a usage error (exit status 2)."""

    exit_status = 2


class TrainingDataError(SeeNerfError):
    """Session arrays have the wrong shape, dtype or range for training."""


class CheckpointError(SeeNerfError):
    """A run folder or checkpoint is missing or does not match its configuration."""


class TrainingStopped(SeeNerfError):
    """Training was asked to stop (SIGTERM, Ctrl-C) and saved a checkpoint at its last step.

    Args:
        message: what happened and how to resume.
        signal_number: the signal that asked; the exit status is 128 + it, as for a process
            the signal ended.
    """

    def __init__(self, message: str, signal_number: int):
        super().__init__(message)
        self.exit_status = 128 + signal_number
