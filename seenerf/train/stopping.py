"""Stop requests (SIGTERM, Ctrl-C) turned into a flag the training loop reads between steps."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

__all__ = ["StopRequest", "stop_requests"]

_SIGNALS = (signal.SIGTERM, signal.SIGINT)


@dataclass
class StopRequest:
    """The signal that asked training to stop, or None while none has."""

    signal_number: int | None = None

    @property
    def signal_name(self) -> str:
        """``SIGTERM`` or ``SIGINT`` (Ctrl-C)."""
        return "Ctrl-C" if self.signal_number == signal.SIGINT else "SIGTERM"


@contextmanager
def stop_requests() -> Iterator[StopRequest]:
    """While inside, SIGTERM and SIGINT only set the flag; the previous handlers come back after.

    Outside the main thread (where Python runs no handler) the flag never rises.
    """
    request = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield request
        return

    def note(signal_number, frame) -> None:
        request.signal_number = signal_number

    previous = {number: signal.signal(number, note) for number in _SIGNALS}
    try:
        yield request
    finally:
        for number, handler in previous.items():  # None: not set from Python; the default
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
