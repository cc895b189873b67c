"""Defaults of the session contract that every stage shares: bins per exposure and threshold."""

from __future__ import annotations

__all__ = ["DEFAULT_BINS", "DEFAULT_THRESHOLD"]

DEFAULT_BINS = 4
"""Event bins per exposure b when neither the user nor the session names one (the paper's value)."""

DEFAULT_THRESHOLD = 0.3
"""Contrast threshold when neither the caller nor the camera states one: the nominal DAVIS
threshold at default biases, natural-log units per event."""
