"""The emulated DAVIS346 itself: identity, register file, word stream and injected faults."""

from __future__ import annotations

import errno
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import usb.core

from davis_io.chips import SENSOR_SIZES
from davis_io.colorfilter import DEVICE_COLOR_FILTERS
from davis_io.types import ColorFilter, PacketSource
from davis_io.usb import protocol as P
from davis_io.usb.emulated_stream import SourceWords, StreamChunk, StreamFaults
from davis_io.usb.layout import SensorLayout

__all__ = ["EmulatedDavis346", "RegisterRequest", "usb_error"]

_SPLIT_SIZES = (1, 4095, 3, 777, 2, 8191, 5)
"""Transfer sizes (bytes) cycled through when transfers split words."""
_USB_ERRORS = {
    "stall": ("Pipe error", -9, errno.EPIPE),
    "gone": ("No such device (it may have been disconnected)", -4, errno.ENODEV),
    "access": ("Access denied (insufficient permissions)", -3, errno.EACCES),
    "busy": ("Resource busy", -6, errno.EBUSY),
}


@dataclass(frozen=True)
class RegisterRequest:
    """One vendor write request as the device received it.

    Attributes:
        request: 0xBF (single write) or 0xC2 (multi-write).
        writes: ``(module, parameter, value)`` entries, in order.
    """

    request: int
    writes: tuple[tuple[int, int, int], ...]


def usb_error(kind: str) -> usb.core.USBError:
    """The pyusb error libusb raises for ``kind``: "stall", "gone", "access" or "busy"."""
    return usb.core.USBError(*_USB_ERRORS[kind])


def _default_registers(color_filter: ColorFilter) -> dict[tuple[int, int], int]:
    columns, rows = SENSOR_SIZES["DAVIS346"]
    regs = {
        (P.Module.SYSINFO, P.SysInfo.LOGIC_VERSION): P.REQUIRED_LOGIC_VERSION,
        (P.Module.SYSINFO, P.SysInfo.CHIP_IDENTIFIER): P.ChipId.DAVIS346B,
        (P.Module.SYSINFO, P.SysInfo.DEVICE_IS_MASTER): 1,
        (P.Module.SYSINFO, P.SysInfo.LOGIC_CLOCK): 90,
        (P.Module.SYSINFO, P.SysInfo.ADC_CLOCK): 30,
        (P.Module.SYSINFO, P.SysInfo.USB_CLOCK): 30,
        (P.Module.SYSINFO, P.SysInfo.CLOCK_DEVIATION): 1000,
        (P.Module.SYSINFO, P.SysInfo.LOGIC_PATCH): 1,
        (P.Module.DVS, P.Dvs.SIZE_COLUMNS): columns,
        (P.Module.DVS, P.Dvs.SIZE_ROWS): rows,
        (P.Module.APS, P.Aps.SIZE_COLUMNS): columns,
        (P.Module.APS, P.Aps.SIZE_ROWS): rows,
        (P.Module.APS, P.Aps.COLOR_FILTER): DEVICE_COLOR_FILTERS.index(color_filter),
        (P.Module.APS, P.Aps.HAS_GLOBAL_SHUTTER): 1,
        (P.Module.IMU, P.Imu.TYPE): 1,
        (P.Module.IMU, P.Imu.ACCEL_FULL_SCALE): 1,
        (P.Module.IMU, P.Imu.GYRO_FULL_SCALE): 1,
        (P.Module.MUX, P.Mux.HAS_STATISTICS): 1,
        (P.Module.DVS, P.Dvs.HAS_STATISTICS): 1,
    }
    for flag in (
        P.Dvs.HAS_PIXEL_FILTER,
        P.Dvs.HAS_BACKGROUND_ACTIVITY_FILTER,
        P.Dvs.HAS_ROI_FILTER,
        P.Dvs.HAS_SKIP_FILTER,
        P.Dvs.HAS_POLARITY_FILTER,
    ):
        regs[(P.Module.DVS, flag)] = 1
    return regs


_STREAM_SWITCHES = (
    (P.Module.USB, P.Usb.RUN),
    (P.Module.MUX, P.Mux.RUN),
    (P.Module.DVS, P.Dvs.RUN),
    (P.Module.APS, P.Aps.RUN),
    (P.Module.IMU, P.Imu.RUN_ACCELEROMETER),
    (P.Module.IMU, P.Imu.RUN_GYROSCOPE),
    (P.Module.IMU, P.Imu.RUN_TEMPERATURE),
    (P.Module.EXTINPUT, P.ExtInput.RUN_DETECTOR),
)
"""Registers that must all be 1 for the emulated stream to flow (the end of dataStart)."""


@dataclass
class EmulatedDavis346:
    """One emulated camera: identity, a register file, a word stream and faults.

    The stream starts with a timestamp reset when TIMESTAMP_RUN goes from 0 to 1 and flows while
    USB RUN, MUX RUN and every producer the source feeds (DVS, APS, IMU, external input) are 1,
    i.e. once the host's start sequence is complete: the recorded words interleave all kinds, so
    they cannot flow while part of the sensor is still off. A host-requested TIMESTAMP_RESET is
    logged, not acted on: the source's clock cannot restart mid-encoding;
    ``StreamFaults.reset_at_us`` emulates resets.

    Args:
        source: packets to stream (a recording or the emulator); None streams nothing.
        serial: serial-number string (at most 8 characters on a real device).
        firmware: firmware version (low byte of bcdDevice).
        logic_patch: SYSINFO logic patch level; ``logic_version`` SYSINFO logic version.
        color_filter: what APS COLOR_FILTER reports.
        faults: stream faults to inject.
        chunks: a ready word producer instead of ``source`` (e.g. :func:`looped_words`).
        realtime: deliver words no faster than their stream time (for throughput benchmarks).
        deny_access: opening fails with a permission error.
        in_use_elsewhere: another program holds interface 0 (claiming fails, busy).
        record_delivered: keep a copy of every byte delivered (``delivered``), for tests.
        product_id: USB product id (FX3 by default).
        address: USB device address on bus 1.
    """

    source: PacketSource | None = None
    serial: str = "00000104"
    firmware: int = 6
    logic_version: int = P.REQUIRED_LOGIC_VERSION
    logic_patch: int = 1
    color_filter: ColorFilter = ColorFilter.MONO
    faults: StreamFaults = field(default_factory=StreamFaults)
    chunks: Iterator[StreamChunk] | None = None
    realtime: bool = False
    deny_access: bool = False
    in_use_elsewhere: bool = False
    record_delivered: bool = False
    product_id: int = P.FX3_PRODUCT_ID
    address: int = 1

    def __post_init__(self):
        self.registers = _default_registers(self.color_filter)
        self.registers[(P.Module.SYSINFO, P.SysInfo.LOGIC_VERSION)] = self.logic_version
        self.registers[(P.Module.SYSINFO, P.SysInfo.LOGIC_PATCH)] = self.logic_patch
        self.requests: list[RegisterRequest] = []
        self.connected = True
        self.claimed = False
        self.is_open = False
        self.stalled = False
        self.bytes_delivered = 0
        self.delivered = bytearray()
        self.clear_halt_count = 0
        self._buffer = bytearray()
        self._offset = 0
        self._producer: Iterator[StreamChunk] | None = None
        self._exhausted = False
        self._split_index = 0
        self._lock = threading.Lock()
        self._started_at = 0.0

    @property
    def writes(self) -> list[tuple[int, int, int]]:
        """Every register write received, flattened in order."""
        return [write for request in self.requests for write in request.writes]

    @property
    def time_origin_us(self) -> int | None:
        """Source time at device time 0 (known once streaming started), µs."""
        return getattr(self._producer, "time_origin_us", None)

    @property
    def exhausted(self) -> bool:
        """True once every word of the source has been delivered."""
        return self._exhausted and self._offset == len(self._buffer)

    def layout(self) -> SensorLayout:
        """The sensor layout the registers describe."""
        reg = self.registers
        return SensorLayout(
            dvs_columns=reg[(P.Module.DVS, P.Dvs.SIZE_COLUMNS)],
            dvs_rows=reg[(P.Module.DVS, P.Dvs.SIZE_ROWS)],
            aps_columns=reg[(P.Module.APS, P.Aps.SIZE_COLUMNS)],
            aps_rows=reg[(P.Module.APS, P.Aps.SIZE_ROWS)],
            imu_type=reg[(P.Module.IMU, P.Imu.TYPE)],
        )

    def read_register(self, module: int, param: int) -> int:
        """Value of one register (0 when never written), as a config read returns it."""
        return self.registers.get((module, param), 0)

    def write_registers(self, request: int, writes: list[tuple[int, int, int]]) -> None:
        """Apply and log one vendor write request."""
        self.requests.append(RegisterRequest(request, tuple(writes)))
        for module, param, value in writes:
            before = self.registers.get((module, param), 0)
            self.registers[(module, param)] = value
            if (module, param) == (P.Module.MUX, P.Mux.TIMESTAMP_RUN) and value and not before:
                self._start_stream()
            if (module, param) == (P.Module.MUX, P.Mux.TIMESTAMP_RESET):
                self.registers[(module, param)] = 0  # an impulse: reads back as 0

    def _start_stream(self) -> None:
        """Timestamp generator started: a timestamp reset word, then the source's words."""
        self._buffer = bytearray(np.array([P.Special.TIMESTAMP_RESET], "<u2").tobytes())
        self._offset = 0
        self._started_at = time.monotonic()
        if self.chunks is not None:
            self._producer = self.chunks
        elif self.source is not None:
            reg = self.registers
            adc = (
                reg[(P.Module.SYSINFO, P.SysInfo.ADC_CLOCK)]
                * reg[(P.Module.SYSINFO, P.SysInfo.CLOCK_DEVIATION)]
                / 1000
            )
            self._producer = SourceWords(
                self.source,
                self.layout(),
                self.faults,
                adc_clock_mhz=adc,
                accel_scale=reg[(P.Module.IMU, P.Imu.ACCEL_FULL_SCALE)],
                gyro_scale=reg[(P.Module.IMU, P.Imu.GYRO_FULL_SCALE)],
            )
        self._exhausted = self._producer is None

    def _streaming(self) -> bool:
        return all(self.read_register(module, param) for module, param in _STREAM_SWITCHES)

    def _refill(self, wanted: int) -> None:
        while len(self._buffer) - self._offset < wanted and not self._exhausted:
            try:
                chunk = next(self._producer)
            except StopIteration:
                self._exhausted = True
                return
            if self.realtime:
                delay = chunk.stream_time_us / 1e6 - (time.monotonic() - self._started_at)
                if delay > 0:
                    time.sleep(delay)
            self._count_dropped(chunk.dropped_events)
            self._buffer += chunk.words.astype("<u2", copy=False).tobytes()

    def _count_dropped(self, count: int) -> None:
        if count:
            key_high = (P.Module.MUX, P.Mux.STATISTICS_DVS_DROPPED)
            key_low = (P.Module.MUX, P.Mux.STATISTICS_DVS_DROPPED + 1)
            total = (self.registers.get(key_high, 0) << 32 | self.registers.get(key_low, 0)) + count
            self.registers[key_high], self.registers[key_low] = total >> 32, total & 0xFFFFFFFF

    def bulk_read(self, size: int, timeout_ms: int) -> bytes:
        """Bytes of the next transfer (up to ``size``); raises the injected faults."""
        with self._lock:
            if not self.connected:
                raise usb_error("gone")
            if self.stalled:
                raise usb_error("stall")
            if not self._streaming():
                time.sleep(min(timeout_ms, 50) / 1000)
                raise usb.core.USBTimeoutError("Operation timed out", -7, errno.ETIMEDOUT)
            if self.faults.split_transfers:
                size = min(size, _SPLIT_SIZES[self._split_index % len(_SPLIT_SIZES)])
                self._split_index += 1
            size = self._apply_cut(size)
            self._refill(size)
            if self._offset == len(self._buffer):
                time.sleep(min(timeout_ms, 20) / 1000)
                raise usb.core.USBTimeoutError("Operation timed out", -7, errno.ETIMEDOUT)
            data = self._take(size)
            self.bytes_delivered += len(data)
            if self.record_delivered:
                self.delivered += data
            return data

    def _take(self, size: int) -> bytes:
        """Up to ``size`` buffered bytes, front first (compacting the buffer now and then)."""
        data = bytes(self._buffer[self._offset : self._offset + size])
        self._offset += len(data)
        if self._offset > len(self._buffer) // 2:
            del self._buffer[: self._offset]
            self._offset = 0
        return data

    def _apply_cut(self, size: int) -> int:
        """Shrink a transfer so it ends exactly where a stall or disconnect is due; raise there."""
        for limit, kind in (
            (self.faults.stall_after_bytes, "stall"),
            (self.faults.disconnect_after_bytes, "gone"),
        ):
            if limit is None:
                continue
            if self.bytes_delivered >= limit:
                self.stalled |= kind == "stall"
                self.connected &= kind != "gone"
                raise usb_error(kind)
            size = min(size, limit - self.bytes_delivered)
        return size
