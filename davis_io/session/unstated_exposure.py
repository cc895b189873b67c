"""Frames whose source states no exposure (its start and end alike): an assumed one, said so.

A file converted from another format may keep a frame's time stamp and drop its exposure (an
AEDAT 4.0 frame whose exposure field is 0). Such a frame has no window for its events and a
zero exposure for its brightness; nothing downstream can use it. The recorder gives it the window
``[start, start + E]`` (AEDAT 4.0's time stamp is the start of exposure), with ``E``:

* the exposure given for the recording (``seecap record --replay FILE --exposure 0.05``);
* else half the time to the next frame's start: an exposure fills some share of the frame
  interval, and half is the middle of what it can be;
* for the last frame (or one whose next starts with it), the one assumed before it; before
  any, :data:`LONE_FRAME_US`.

Every such length is an assumption: the session states it (``exposure_assumed_us``) and the
recorder warns with the way to give the real one.
"""

from __future__ import annotations

import dataclasses
import statistics

from davis_io.types import Frame

__all__ = ["LONE_FRAME_US", "UnstatedExposures"]

LONE_FRAME_US = 10_000
"""The exposure assumed for a frame with neither an exposure nor a next frame, µs."""


class UnstatedExposures:
    """Passes frames on in order, each that states no exposure given an assumed one.

    Such a frame is held back until the next frame's start is known (one at most).

    Args:
        given_us: the exposure given for the recording, µs (None: assumed from the interval).
    """

    def __init__(self, given_us: int | None = None):
        self.given_us = given_us
        self.assumed_us: list[int] = []
        """The exposure each unstated frame was given, in order."""
        self._held: Frame | None = None

    def accept(self, frame: Frame) -> list[Frame]:
        """The frames ready to go on: a held one first, then ``frame`` unless it is held."""
        ready = self.released_by(frame)
        if frame.exposure_end_us > frame.exposure_start_us:
            ready.append(frame)
        elif self.given_us is not None:
            ready.append(self._assumed(frame, self.given_us))
        else:
            self._held = frame
        return ready

    def released_by(self, frame: Frame) -> list[Frame]:
        """The held frame, if any, now that the next frame's start is known.

        ``frame`` itself goes no further (a frame past the recording's limit).
        """
        if self._held is None:
            return []
        held, self._held = self._held, None
        half_us = (frame.exposure_start_us - held.exposure_start_us) // 2
        return [self._assumed(held, half_us if half_us > 0 else self._earlier())]

    def finish(self) -> list[Frame]:
        """The frame still held, if any, with the exposure of the one before it."""
        if self._held is None:
            return []
        frame, self._held = self._held, None
        return [self._assumed(frame, self._earlier())]

    @property
    def median_us(self) -> int | None:
        """The median assumed exposure, µs (None: every frame stated its own)."""
        return int(statistics.median(self.assumed_us)) if self.assumed_us else None

    def _earlier(self) -> int:
        """The exposure assumed last, or :data:`LONE_FRAME_US` before any."""
        return self.assumed_us[-1] if self.assumed_us else LONE_FRAME_US

    def _assumed(self, frame: Frame, length_us: int) -> Frame:
        self.assumed_us.append(int(length_us))
        return dataclasses.replace(frame, exposure_end_us=frame.exposure_start_us + length_us)
