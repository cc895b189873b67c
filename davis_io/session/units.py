"""Parsing of durations given on the command line (seconds by default; us, ms, s, m, min, h)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable

from davis_io.errors import UsageError

__all__ = ["parse_duration_us", "seconds_argument"]

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
    value_us = round(float(match.group(1)) * _SCALE_US[match.group(2)])
    if value_us <= 0:
        raise UsageError(f"{what} {text!r} must be > 0 (at least 1 µs)")
    return value_us


def seconds_argument(what: str) -> Callable[[str], float]:
    """An argparse ``type=`` that reads a duration into seconds; bad text is a usage error.

    Args:
        what: the option's name in the message (``--time-budget``).
    """

    def seconds(text: str) -> float:
        try:
            return parse_duration_us(text, what=what) / 1e6
        except UsageError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    return seconds
