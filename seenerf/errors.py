"""Typed errors of the See-NeRF trainer; each message says what was wrong, where, and what to do."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TypeVar

from davis_io import SeecapError

__all__ = ["CheckpointError", "ConfigError", "SeeNerfError", "TrainingDataError", "by_name"]

T = TypeVar("T")


class SeeNerfError(SeecapError):
    """Base of every error raised on purpose by ``seenerf`` (caught by the ``seecap`` CLI)."""


class ConfigError(SeeNerfError):
    """A preset, variant or configuration value is unknown or out of range."""


class TrainingDataError(SeeNerfError):
    """Session arrays have the wrong shape, dtype or range for training."""


class CheckpointError(SeeNerfError):
    """A run folder or checkpoint is missing or does not match its configuration."""


def by_name(table: Mapping[str, T], what: str, name: str) -> T:
    """The entry of ``table`` called ``name`` (a preset, a variant).

    Raises:
        ConfigError: unknown name (the message lists the known ones).
    """
    if name not in table:
        raise ConfigError(f"unknown {what} {name!r}; choose one of: {', '.join(table)}")
    return table[name]
