"""APS frame assembly for AEDAT 2.0: reset and signal reads into frames with exposure times."""

from __future__ import annotations

import numpy as np

from davis_io.types import Frame

__all__ = ["ApsAssembler", "correlated_double_sample"]

SATURATED = 1023
"""10-bit value given to pixels whose reset read is too low or whose signal read is 0."""
MIN_RESET = 384
"""Reset reads below this (after the ADC gain) mark a saturated pixel (libcaer's CDS rule)."""


def correlated_double_sample(reset: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """Return the 10-bit image ``reset - signal`` with libcaer's saturation rule.

    A pixel whose reset read is below 384 or whose signal read is 0 is white (1023); any other
    difference is clamped to 0..1023 (davis-protocol.md §3.6).
    """
    difference = np.clip(reset.astype(np.int32) - signal.astype(np.int32), 0, SATURATED)
    saturated = (reset < MIN_RESET) | (signal == 0)
    return np.where(saturated, SATURATED, difference).astype(np.uint16)


class ApsAssembler:
    """Assemble APS samples, fed in file order and in pieces of any size, into frames.

    Times follow jAER's derivation from pixel read times (davis-protocol.md §3.7, §6.1): start of
    frame = first reset-read pixel (0, 0); start of exposure = last reset-read pixel (W-1, H-1)
    for global shutter or the first reset-read pixel for rolling shutter; end of exposure =
    first signal-read pixel; end of frame = last signal-read pixel, which completes the frame.
    A frame missing any pixel or time is dropped with a note.
    """

    def __init__(self, width: int, height: int, global_shutter: bool = True, adc_gain: int = 1):
        """Prepare empty read buffers for a ``width`` x ``height`` array.

        Args:
            width: APS columns.
            height: APS rows.
            global_shutter: exposure starts after the reset pass (True) or with it (False).
            adc_gain: factor applied to every sample before CDS (2 on DAVIS240, as libcaer).
        """
        self.width, self.height = width, height
        self.global_shutter, self.adc_gain = global_shutter, adc_gain
        self._reads = np.zeros((2, height, width), dtype=np.int32)
        self._seen = np.zeros((2, height, width), dtype=bool)
        self._times: dict[str, int] = {}
        self._active = False

    def feed(
        self, t: np.ndarray, x: np.ndarray, y: np.ndarray, readout: np.ndarray, sample: np.ndarray
    ) -> tuple[list[Frame], list[str]]:
        """Consume samples (top-left coordinates, readout 0 reset / 1 signal); return new frames.

        Returns:
            The frames completed by these samples and notes about dropped frames.
        """
        first = (x == 0) & (y == 0)
        last = (x == self.width - 1) & (y == self.height - 1)
        frames, notes, done = [], [], 0
        for index in np.flatnonzero(first | last).tolist():
            self._store(x, y, readout, sample, slice(done, index))
            kind = (
                "first" if first[index] else "last",
                "reset" if readout[index] == 0 else "signal",
            )
            if kind == ("first", "reset"):
                notes += self._start(int(t[index]))
            self._store(x, y, readout, sample, slice(index, index + 1))
            frame = self._marker(kind, int(t[index]), notes)
            frames += [frame] if frame is not None else []
            done = index + 1
        self._store(x, y, readout, sample, slice(done, len(t)))
        return frames, notes

    def _start(self, t: int) -> list[str]:
        notes = []
        if self._active:
            notes.append(
                f"APS frame started at {self._times['readout_start_us']} µs never ended; dropped"
            )
        self._seen[:] = False
        self._times = {"readout_start_us": t}
        if not self.global_shutter:
            self._times["exposure_start_us"] = t
        self._active = True
        return notes

    def _store(self, x, y, readout, sample, part: slice) -> None:
        if not self._active or part.start >= part.stop:
            return
        kind, rows, cols = readout[part], y[part], x[part]
        self._reads[kind, rows, cols] = sample[part].astype(np.int32) * self.adc_gain
        self._seen[kind, rows, cols] = True

    def _marker(self, kind: tuple[str, str], t: int, notes: list[str]) -> Frame | None:
        if not self._active:
            return None
        if kind == ("last", "reset") and self.global_shutter:
            self._times["exposure_start_us"] = t
        elif kind == ("first", "signal"):
            self._times["exposure_end_us"] = t
        elif kind == ("last", "signal"):
            self._active = False
            self._times["readout_end_us"] = t
            if len(self._times) == 4 and self._seen.all():
                image = correlated_double_sample(self._reads[0], self._reads[1])
                return Frame(image=image, bit_depth=10, **self._times)
            notes.append(
                f"APS frame started at {self._times['readout_start_us']} µs is "
                f"incomplete ({int(self._seen.sum())} of {self._seen.size} reads); "
                "dropped"
            )
        return None
