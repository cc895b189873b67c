"""Parsing of durations given on the command line (seconds by default; us, ms, s, m, min, h)."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable

from davis_io.errors import UsageError
from davis_io.session.bounds import Bounds

__all__ = ["MAX_DURATION_US", "parse_duration_us", "seconds_argument"]

MAX_DURATION_US = 30 * 86_400 * 1_000_000
"""The longest duration any option takes: 30 days."""

_DURATION = re.compile(
    r"^\s*([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(s|ms|us|µs|m|min|h)?\s*$"
)
_SCALE_US = {
    None: 1_000_000,
    "s": 1_000_000,
    "ms": 1_000,
    "us": 1,
    "µs": 1,
    "m": 60_000_000,
    "min": 60_000_000,
    "h": 3_600_000_000,
}


def parse_duration_us(text: str, *, what: str = "duration") -> int:
    """Parse ``"0.15"``, ``"150ms"``, ``"150000us"``, ``"10m"`` or ``"1.5h"`` into whole µs.

    Args:
        text: the value as typed; a bare number is in seconds.
        what: name of the option, used in the error message.

    Returns:
        The duration in µs, rounded to the nearest microsecond.

    Raises:
        UsageError: the text is not a positive duration.
    """
    match = _DURATION.match(str(text))
    if not match:
        raise UsageError(
            f"{what} {text!r} is not a duration: give seconds (0.15), milliseconds (150ms), "
            "microseconds (150000us), minutes (10m) or hours (1.5h)"
        )
    value = float(match.group(1)) * _SCALE_US[match.group(2)]
    if not math.isfinite(value) or value > MAX_DURATION_US:
        raise UsageError(f"{what} {text!r} is too long: at most 30 days")
    value_us = round(value)
    if value_us <= 0:
        raise UsageError(f"{what} {text!r} must be > 0 (at least 1 µs)")
    return value_us


def seconds_argument(what: str, bounds: Bounds | None = None) -> Callable[[str], float]:
    """An argparse ``type=`` that reads a duration into seconds; bad text is a usage error.

    Args:
        what: the option's name in the message (``--time-budget``).
        bounds: the seconds the option takes (None: any duration up to 30 days).
    """

    def seconds(text: str) -> float:
        try:
            value = parse_duration_us(text, what=what) / 1e6
            return value if bounds is None else bounds.check(what, value)
        except UsageError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    return seconds
