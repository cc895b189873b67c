"""The one check of a number given by a user or read back from a file: finite, in range, units.

Every numeric option of every verb and every number read back from ``session.json`` or a run's
``config.json`` is checked against its :class:`Bounds` before anything uses it, so NaN, an
infinity, a negative size or a request too large for any real recording is a usage error that
names the option, the value and the range, never a failure deep inside (exit status 2).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from dataclasses import dataclass

from davis_io.errors import UsageError

__all__ = ["Bounds"]


@dataclass(frozen=True)
class Bounds:
    """The values a number may take.

    Attributes:
        low: smallest value (excluded when ``low_open``).
        high: largest value (excluded when ``high_open``).
        unit: the unit, for messages (``"s"``, ``"bins"``).
        integer: only whole numbers.
        low_open: ``low`` itself is excluded.
        high_open: ``high`` itself is excluded.
    """

    low: float
    high: float
    unit: str = ""
    integer: bool = False
    low_open: bool = False
    high_open: bool = False

    def describe(self) -> str:
        """The range in words, e.g. ``a whole number from 1 to 64 bins``."""
        kind = "a whole number" if self.integer else "a number"
        low = f"{'above' if self.low_open else 'from'} {_number(self.low)}"
        high = f"{'below' if self.high_open else 'to'} {_number(self.high)}"
        return f"{kind} {low} {high}{' ' + self.unit if self.unit else ''}"

    def holds(self, value) -> bool:
        """True when ``value`` is a number of the right kind inside the range."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        if not math.isfinite(value) or (self.integer and value != int(value)):
            return False
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def problem(self, what: str, value) -> str | None:
        """What is wrong with ``value`` in one line naming ``what``; None when it holds."""
        return (
            None
            if self.holds(value)
            else f"{what} {value!r} is out of range: give {self.describe()}"
        )

    def check(self, what: str, value):
        """``value`` when it holds.

        Raises:
            UsageError: naming ``what`` (an option, or a file's field), the value and the range.
        """
        problem = self.problem(what, value)
        if problem is not None:
            raise UsageError(problem)
        return int(value) if self.integer else value

    def argument(self, what: str, parse: Callable[[str], float] | None = None):
        """An argparse ``type=`` reading a number (or ``parse(text)``) and checking it."""

        def checked(text: str):
            try:
                value = (parse or (int if self.integer else float))(text)
            except ValueError:
                raise argparse.ArgumentTypeError(
                    f"{text!r} is not a number: give {self.describe()}"
                ) from None
            except UsageError as error:
                raise argparse.ArgumentTypeError(str(error)) from None
            if not self.holds(value):
                raise argparse.ArgumentTypeError(
                    f"{text!r} is out of range: give {self.describe()}"
                )
            return value

        return checked


def _number(value: float) -> str:
    """``10000000`` as ``10000000``, ``2592000.0`` as ``2592000``, ``1e-06`` as ``1e-06``."""
    return str(int(value)) if value == int(value) and abs(value) < 1e15 else f"{value:g}"
