"""Warnings about recordings that are read anyway (truncation, skipped data)."""

from __future__ import annotations

import warnings

__all__ = ["RecordingWarning", "warn_note"]


class RecordingWarning(UserWarning):
    """A recording was read with something skipped or missing; the message says what and where."""


def warn_note(message: str) -> str:
    """Emit ``message`` as a :class:`RecordingWarning` and return it for a packet's ``notes``."""
    warnings.warn(message, RecordingWarning, stacklevel=3)
    return message
