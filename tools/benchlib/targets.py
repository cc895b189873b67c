"""Every goal the benchmarks judge against, in one table: the reports and tools read it here.

Each goal is a :class:`Target` (a comparison and a limit in the figure's unit) or a
:class:`Band` (a figure that must lie between two limits). Changing a goal here changes every
verdict that uses it: the Targets table, the blind benchmark's target columns, the capture
tools' own exit codes and the sharing report.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass

__all__ = [
    "BINNING_S",
    "BLIND_LOG_CONTRAST",
    "BLIND_ORACLE_GAP_DB",
    "BLIND_POSE_MEDIAN_DEG",
    "BLIND_THRESHOLD_ERROR",
    "BLIND_WHITE_BOX_GAP_DB",
    "BUSY_SHARE",
    "CAPTURE_TARGETS",
    "DECODE_RATIO",
    "DROPPED_EVENTS",
    "END_TO_END_MIN",
    "FAST_OVER_PAPER_RAYS",
    "FULL_OVER_BASE_DB",
    "FULL_OVER_NO_EVENTS_DB",
    "POSES_S",
    "QUEUE_OVERFLOW",
    "RENDER_VIEW_S",
    "SCENE_HDR_DB",
    "SCENE_NOVEL_DB",
    "SCENE_ORACLE_GAP_DB",
    "USB_DECODER_MWORDS_S",
    "Band",
    "Target",
]

_COMPARE = {">=": operator.ge, "<=": operator.le, "<": operator.lt, "==": operator.eq}
_SYMBOL = {">=": "≥", "<=": "≤", "<": "<", "==": "="}


@dataclass(frozen=True)
class Target:
    """A figure compared with a limit.

    Attributes:
        comparison: ``>=``, ``<=``, ``<`` or ``==``.
        limit: the limit, in the figure's unit.
    """

    comparison: str
    limit: float

    def met(self, value: float | None) -> bool | None:
        """Whether ``value`` meets the goal (None: not measured)."""
        return None if value is None else bool(_COMPARE[self.comparison](value, self.limit))

    @property
    def goal(self) -> str:
        """The goal as a table cell, for example ``>= 30``."""
        return f"{self.comparison} {self.limit:g}"

    @property
    def in_words(self) -> str:
        """The goal inside a sentence or a column name, for example ``≤ 3``."""
        return f"{_SYMBOL[self.comparison]} {self.limit:g}"


@dataclass(frozen=True)
class Band:
    """A figure that must lie within ``[low, high]``."""

    low: float
    high: float

    def met(self, value: float | None) -> bool | None:
        """Whether ``value`` lies in the band (None: not measured)."""
        return None if value is None else self.low <= value <= self.high

    @property
    def goal(self) -> str:
        """The band as text, for example ``0.8-1.2``."""
        return f"{self.low:g}-{self.high:g}"


# The trainer on the main session (the Targets table).
FULL_OVER_BASE_DB = Target(">=", 3.0)
"""``full`` above ``base`` (no event-based CRF, no blur model), HDR PSNR dB."""
FULL_OVER_NO_EVENTS_DB = Target(">=", 1.0)
"""``full`` above ``no-events``, HDR PSNR dB: what the events add."""
FAST_OVER_PAPER_RAYS = Target(">=", 100.0)
"""Rays per second of the ``fast`` preset over the ``paper`` preset, same process."""

# Every benchmark scene (the Targets table and the scene table).
SCENE_HDR_DB = Target(">=", 30.0)
"""``full``'s HDR PSNR at the top budget, dB."""
SCENE_NOVEL_DB = Target(">=", 30.0)
"""``full``'s novel-exposure PSNR at the top budget, dB."""
SCENE_ORACLE_GAP_DB = Target("<=", 2.0)
"""``oracle`` minus ``full``, HDR PSNR dB."""
RENDER_VIEW_S = Target("<=", 1.0)
"""Seconds to render one held-out view."""
POSES_S = Target("<=", 60.0)
"""Seconds of the pose step from the recording (``tools/bench_poses.py``: 16 views x 5)."""
END_TO_END_MIN = Target("<=", 10.5)
"""Minutes from the recording to scores: poses, then every process of ``full``'s runs (a
ten-minute budget may end 5 % late)."""

# The capture side (each tool's own verdict and the Targets table).
DECODE_RATIO = Target(">=", 1.0)
"""AEDAT 4.0 decoding speed over dv-processing's, same file, same run."""
USB_DECODER_MWORDS_S = Target(">=", 50.0)
"""USB word decoder, M words/s."""
QUEUE_OVERFLOW = Target("==", 0.0)
"""Packets the host queue dropped end to end."""
BINNING_S = Target("<", 0.5)
"""Seconds to bin 1 M events into exposure-synchronised bins."""
DROPPED_EVENTS = Target("==", 0.0)
"""Events the recorder dropped, paced as a live camera."""

CAPTURE_TARGETS = {
    "bench_decode.py": {"ratio": DECODE_RATIO},
    "bench_usb.py": {"decoder_mwords_s": USB_DECODER_MWORDS_S, "e2e_overflow": QUEUE_OVERFLOW},
    "bench_record.py": {
        "binning_b4_s": BINNING_S,
        "binning_b6_s": BINNING_S,
        "drops": DROPPED_EVENTS,
    },
}
"""Capture tool -> its figures' targets (the figures: :data:`benchlib.capture.CAPTURE_BENCHES`)."""

# The blind camera (each session's target columns).
BLIND_LOG_CONTRAST = Band(0.8, 1.2)
"""``full``'s log contrast against the truth."""
BLIND_WHITE_BOX_GAP_DB = Target("<=", 1.0)
"""``white-box`` minus ``full``, dB: what the calibration costs."""
BLIND_ORACLE_GAP_DB = Target("<=", 3.0)
"""``oracle`` minus ``full``, dB."""
BLIND_POSE_MEDIAN_DEG = Target("<=", 0.5)
"""Median rotation error of the estimated poses against the truth, degrees."""
BLIND_THRESHOLD_ERROR = Target("<=", 0.10)
"""Relative error of each measured threshold, where the pixels are clean."""

# Sharing the machine.
BUSY_SHARE = Target(">=", 0.5)
"""A fit beside one busy process: its training throughput over its throughput alone."""
