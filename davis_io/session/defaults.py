"""Defaults and ranges of the session contract that every stage shares (bins, threshold, sizes)."""

from __future__ import annotations

from davis_io.session.bounds import Bounds

__all__ = [
    "BINS",
    "DEFAULT_BINS",
    "DEFAULT_THRESHOLD",
    "EXPOSURE_S",
    "FRAME_COUNT",
    "SEED",
    "THRESHOLD",
]

DEFAULT_BINS = 4
"""Event bins per exposure b when neither the user nor the session names one (the paper's value)."""

DEFAULT_THRESHOLD = 0.3
"""Contrast threshold when neither the caller nor the camera states one: the nominal DAVIS
threshold at default biases, natural-log units per event."""

BINS = Bounds(1, 64, "bins", integer=True)
"""Event bins per exposure b: 4 or 6 are usual; 64 cuts a 250 ms exposure into 4 ms bins."""

THRESHOLD = Bounds(0.01, 2.0, "ln per event", low_open=False)
"""A DVS contrast threshold a user may state (a DAVIS's are a few tenths)."""

EXPOSURE_S = Bounds(1e-6, 10.0, "s")
"""An APS exposure: 1 µs to 10 s."""

FRAME_COUNT = Bounds(1, 10_000_000, "frames", integer=True)
"""Frames a recording may be asked for."""

SEED = Bounds(0, 2**32 - 1, integer=True)
"""A seed of random draws."""
