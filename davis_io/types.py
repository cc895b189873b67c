"""Data records shared by every source, writer and consumer: events, frames, IMU, triggers, packets.

Conventions (DESIGN.md §2): time is ``int64`` microseconds on the device clock; pixel origin is the
top-left corner with y pointing down; polarity is +1 (ON) or -1 (OFF).
"""

from __future__ import annotations

import enum
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import TracebackType
from typing import Protocol, Self, runtime_checkable

import numpy as np

__all__ = [
    "EVENT_DTYPE",
    "IMU_DTYPE",
    "TRIGGER_DTYPE",
    "Closing",
    "ColorFilter",
    "Frame",
    "Packet",
    "PacketSource",
    "SourceInfo",
    "TriggerKind",
    "empty_events",
    "empty_imu",
    "empty_triggers",
]

EVENT_DTYPE = np.dtype([("t", "<i8"), ("x", "<u2"), ("y", "<u2"), ("p", "i1")], align=True)
"""One DVS event: time in µs, column, row (top-left origin), polarity +1 / -1.

The aligned 16-byte layout (three padding bytes after ``p``) is that of AEDAT 4.0's event
struct, so AEDAT 4.0 events are used in place, not copied; numpy keeps an aligned struct
aligned when it joins arrays. The padding bytes are undefined: compare events field by field
(``np.array_equal``), never by their bytes.
"""

IMU_DTYPE = np.dtype(
    [
        ("t", np.int64),
        ("acc_g", np.float32, (3,)),
        ("gyro_dps", np.float32, (3,)),
        ("temperature_c", np.float32),
    ]
)
"""One IMU sample: time in µs, acceleration x/y/z in g, angular rate x/y/z in deg/s, °C."""

TRIGGER_DTYPE = np.dtype([("t", np.int64), ("kind", np.int8)])
"""One trigger or special event: time in µs and a :class:`TriggerKind` value."""


class TriggerKind(enum.IntEnum):
    """Trigger and special-event kinds; the values are AEDAT 4.0's ``TriggerType`` numbers."""

    TIMESTAMP_RESET = 0
    EXTERNAL_SIGNAL_RISING_EDGE = 1
    EXTERNAL_SIGNAL_FALLING_EDGE = 2
    EXTERNAL_SIGNAL_PULSE = 3
    EXTERNAL_GENERATOR_RISING_EDGE = 4
    EXTERNAL_GENERATOR_FALLING_EDGE = 5
    APS_FRAME_START = 6
    APS_FRAME_END = 7
    APS_EXPOSURE_START = 8
    APS_EXPOSURE_END = 9


class ColorFilter(enum.Enum):
    """Colour filter array of the APS (and of the DVS pixels on colour DAVIS chips).

    The name gives the 2x2 pattern read row by row from the top-left pixel, so ``RGGB`` means
    (even row, even column) is red, (even, odd) and (odd, even) green, (odd, odd) blue.
    """

    MONO = "mono"
    RGGB = "RGGB"
    GRBG = "GRBG"
    GBRG = "GBRG"
    BGGR = "BGGR"
    RGWB = "RGWB"
    GRBW = "GRBW"
    WBRG = "WBRG"
    BWGR = "BWGR"

    @property
    def is_color(self) -> bool:
        """True for any pattern other than monochrome."""
        return self is not ColorFilter.MONO


def empty_events() -> np.ndarray:
    """Return a zero-length event array (same dtype as every other event array)."""
    return np.empty(0, dtype=EVENT_DTYPE)


def empty_imu() -> np.ndarray:
    """Return a zero-length IMU array."""
    return np.empty(0, dtype=IMU_DTYPE)


def empty_triggers() -> np.ndarray:
    """Return a zero-length trigger array."""
    return np.empty(0, dtype=TRIGGER_DTYPE)


@dataclass(frozen=True)
class Frame:
    """One APS frame at native depth with its four device timestamps.

    Invariant: ``readout_start_us <= exposure_start_us <= exposure_end_us <= readout_end_us`` for
    DAVIS global-shutter frames (``readout_*`` are the start and end of frame, SOF/EOF). The
    exposure window includes both ends: events with ``exposure_start_us <= t <= exposure_end_us``
    belong to this frame.

    Attributes:
        image: ``(H, W)`` for monochrome or raw mosaic, ``(H, W, C)`` for demosaiced colour
            (channels in RGB order). DAVIS ADC values are 10-bit in ``uint16``; 8-bit sources stay
            ``uint8``.
        exposure_start_us: start of exposure (SOE), µs.
        exposure_end_us: end of exposure (EOE), µs.
        readout_start_us: start of frame (SOF), µs.
        readout_end_us: end of frame (EOF), µs.
        bit_depth: significant bits of ``image`` (10 for DAVIS ADC values, 8 for 8-bit files).
        position: ``(x, y)`` of the frame's top-left pixel on the sensor (ROI offset).
    """

    image: np.ndarray
    exposure_start_us: int
    exposure_end_us: int
    readout_start_us: int
    readout_end_us: int
    bit_depth: int = 10
    position: tuple[int, int] = (0, 0)

    @property
    def exposure_us(self) -> int:
        """Exposure duration in µs (end minus start)."""
        return self.exposure_end_us - self.exposure_start_us

    @property
    def readout_us(self) -> int:
        """Readout duration (start of frame to end of frame) in µs."""
        return self.readout_end_us - self.readout_start_us


@dataclass
class Packet:
    """What every source yields: a batch of time-ordered records of each kind.

    Events, IMU samples and triggers are structured arrays (possibly empty); frames are complete
    frames in order of exposure start. ``dropped_events`` counts events known lost before this
    packet (device FIFO overflow, host queue overflow, dropped transfers) so consumers can flag
    affected frames; ``notes`` carries human-readable warnings (truncation, skipped data);
    ``truncated_at`` is the byte offset at which a recording file ends inside a record: its
    source has nothing more, and what the file held after that offset is lost.
    """

    events: np.ndarray = field(default_factory=empty_events)
    frames: list[Frame] = field(default_factory=list)
    imu: np.ndarray = field(default_factory=empty_imu)
    triggers: np.ndarray = field(default_factory=empty_triggers)
    dropped_events: int = 0
    notes: list[str] = field(default_factory=list)
    truncated_at: int | None = None

    @property
    def is_empty(self) -> bool:
        """True when the packet holds no record of any kind."""
        return not (len(self.events) or self.frames or len(self.imu) or len(self.triggers))


@dataclass(frozen=True)
class SourceInfo:
    """What a source knows about the camera and recording behind it.

    Attributes:
        camera: camera model, e.g. ``"DAVIS346"``.
        serial: serial number string ("" when unknown).
        width: sensor width in pixels.
        height: sensor height in pixels.
        color_filter: colour filter pattern of the sensor.
        origin: ``"usb"``, ``"replay:<file name>"`` or ``"emulator:<scene>"``.
        firmware_version: USB firmware version, when known.
        logic_version: FPGA logic version, when known.
        extra: further facts worth recording (device configuration, file format), JSON-safe.
    """

    camera: str
    serial: str
    width: int
    height: int
    color_filter: ColorFilter = ColorFilter.MONO
    origin: str = ""
    firmware_version: int | None = None
    logic_version: int | None = None
    extra: dict = field(default_factory=dict)


class Closing:
    """Mixin for holders of a resource: ``with`` returns the object, exit calls ``close()``."""

    def close(self) -> None:
        """Release the resource (subclasses override)."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


@runtime_checkable
class PacketSource(Protocol):
    """One interface for live and recorded data: a context manager that iterates packets.

    Camera, AEDAT replay and emulator implement it; the recorder, writers, binning and
    ``seecap inspect`` accept any of them.
    """

    info: SourceInfo

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...

    def __iter__(self) -> Iterator[Packet]: ...
