"""How the report prints a number: fixed decimals, a dash for a missing value."""

from __future__ import annotations

import math

__all__ = ["DASH", "fmt"]

DASH = "—"


def fmt(value: float | None, digits: int = 2) -> str:
    """A number with ``digits`` decimals; a dash for None, NaN or infinity."""
    if value is None or not math.isfinite(value):
        return DASH
    return f"{value:.{digits}f}"
