"""Streaming AEDAT 2.0 (jAER) reader for DAVIS240 and DAVIS346 address layouts."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

import numpy as np

from davis_io.aedat.aedat2_frames import ApsAssembler
from davis_io.aedat.report import FileReader, warn_note
from davis_io.chips import SENSOR_SIZES, identify_chip
from davis_io.errors import FormatError
from davis_io.types import (
    EVENT_DTYPE,
    IMU_DTYPE,
    TRIGGER_DTYPE,
    ColorFilter,
    Packet,
    SourceInfo,
    TriggerKind,
)

__all__ = ["RECORD_DTYPE", "Aedat2Decoder", "Aedat2Reader", "read_header"]

MAGIC = b"#!AER-DAT2.0\r\n"
END_OF_HEADER = b"#End Of ASCII Header"
MAX_HEADER_BYTES = 16 << 20
RECORDS_PER_PACKET = 1 << 18

RECORD_DTYPE = np.dtype([("address", ">u4"), ("t", ">u4")])
"""One body record: big-endian 32-bit address and 32-bit timestamp (µs, wraps)."""

DEFAULT_ACCEL_FULL_SCALE_G = 8
DEFAULT_GYRO_FULL_SCALE_DPS = 1000
_ACCEL_KEY = re.compile(rb'key="[^"]*(?:ImuAccelScale|IMU\.AccelScale)"\s+value="\D*(\d+)"')
_GYRO_KEY = re.compile(rb'key="[^"]*(?:ImuGyroScale|IMU\.GyroScale)"\s+value="\D*(\d+)"')
_EXTERNAL_KINDS = {
    0: TriggerKind.EXTERNAL_SIGNAL_PULSE,  # files before the kind field: any external input
    2: TriggerKind.EXTERNAL_SIGNAL_FALLING_EDGE,
    3: TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE,
    4: TriggerKind.EXTERNAL_SIGNAL_PULSE,
}


class Aedat2Decoder:
    """Pure, stateful decoder of record arrays: DVS, APS frames, IMU and external input.

    Records may be fed in pieces of any size; timestamp unwrapping, frame assembly and IMU
    groups carry over between pieces.
    """

    def __init__(
        self,
        width: int,
        height: int,
        accel_full_scale_g: int = DEFAULT_ACCEL_FULL_SCALE_G,
        gyro_full_scale_dps: int = DEFAULT_GYRO_FULL_SCALE_DPS,
        global_shutter: bool = True,
        adc_gain: int = 1,
    ):
        """Set the array size (for the y flip) and the IMU full scales (one LSB = scale / 32768)."""
        self.width, self.height = width, height
        self.g_per_lsb = accel_full_scale_g / 32768
        self.dps_per_lsb = gyro_full_scale_dps / 32768
        self._frames = ApsAssembler(width, height, global_shutter, adc_gain)
        self._last_t, self._wrap_us = None, 0
        self._pending_imu = np.empty(0, dtype=[("kind", "u1"), ("value", "<i2"), ("t", "<i8")])

    def decode(self, records: np.ndarray) -> Packet:
        """Decode an array of :data:`RECORD_DTYPE` records into one packet."""
        address = records["address"].astype(np.uint32)
        t = self._unwrap(records["t"].astype(np.int64))
        is_aps_or_imu = (address >> 31) == 1
        readout = (address >> 10) & 3
        x_field = ((address >> 12) & 0x3FF).astype(np.int64)
        y_field = ((address >> 22) & 0x1FF).astype(np.int64)
        events = self._dvs(address, t, x_field, y_field, ~is_aps_or_imu & (readout & 1 == 0))
        triggers = self._external(address, t, ~is_aps_or_imu & (readout & 1 == 1))
        imu = self._imu(address, t, is_aps_or_imu & (readout == 3))
        aps = is_aps_or_imu & (readout < 2) & (x_field < self.width) & (y_field < self.height)
        frames, notes = self._frames.feed(
            t[aps],
            x_field[aps],
            self.height - 1 - y_field[aps],
            readout[aps].astype(np.int64),
            address[aps] & 0x3FF,
        )
        return Packet(
            events=events,
            frames=frames,
            imu=imu,
            triggers=triggers,
            notes=[warn_note(note) for note in notes],
        )

    def _unwrap(self, t32: np.ndarray) -> np.ndarray:
        """Unwrap 32-bit timestamps: a backward jump of more than 2^31 µs is one wrap."""
        previous = t32[:1] if self._last_t is None else np.array([self._last_t])
        steps = np.diff(np.concatenate([previous, t32]))
        wraps = np.cumsum(steps < -(1 << 31))
        unwrapped = t32 + self._wrap_us + (wraps << 32)
        if len(t32):
            self._last_t, self._wrap_us = int(t32[-1]), self._wrap_us + (int(wraps[-1]) << 32)
        return unwrapped

    def _dvs(self, address, t, x_field, y_field, mask) -> np.ndarray:
        mask &= (x_field < self.width) & (y_field < self.height)
        events = np.empty(int(mask.sum()), dtype=EVENT_DTYPE)
        events["t"] = t[mask]
        events["x"] = self.width - 1 - x_field[mask]
        events["y"] = self.height - 1 - y_field[mask]
        events["p"] = np.where((address[mask] >> 11) & 1, 1, -1)
        return events

    def _external(self, address, t, mask) -> np.ndarray:
        kinds = address & 0x3FF
        mask &= np.isin(kinds, list(_EXTERNAL_KINDS))
        triggers = np.empty(int(mask.sum()), dtype=TRIGGER_DTYPE)
        triggers["t"] = t[mask]
        lookup = np.zeros(5, dtype=np.int8)
        lookup[list(_EXTERNAL_KINDS)] = [int(kind) for kind in _EXTERNAL_KINDS.values()]
        triggers["kind"] = lookup[kinds[mask]]
        return triggers

    def _imu(self, address, t, mask) -> np.ndarray:
        """Group IMU words into samples of 7 consecutive types 0..6 (others are dropped)."""
        words = np.empty(int(mask.sum()), dtype=self._pending_imu.dtype)
        words["kind"] = (address[mask] >> 28) & 7
        words["value"] = ((address[mask] >> 12) & 0xFFFF).astype(np.uint16).view(np.int16)
        words["t"] = t[mask]
        words = np.concatenate([self._pending_imu, words])
        if len(words) >= 7:
            windows = np.lib.stride_tricks.sliding_window_view(words["kind"], 7)
            starts = np.flatnonzero((windows == np.arange(7)).all(axis=1))
        else:
            starts = np.empty(0, dtype=np.int64)
        tail = starts[-1] + 7 if len(starts) else 0
        open_starts = np.flatnonzero(words["kind"][tail:] == 0)
        self._pending_imu = words[tail + open_starts[-1] :] if len(open_starts) else words[:0]
        if len(self._pending_imu) >= 7:
            self._pending_imu = self._pending_imu[:0]
        groups = words["value"][starts[:, None] + np.arange(7)].astype(np.float64)
        imu = np.empty(len(starts), dtype=IMU_DTYPE)
        imu["t"] = words["t"][starts]
        imu["acc_g"] = groups[:, 0:3] * self.g_per_lsb
        imu["temperature_c"] = groups[:, 3] / 340 + 35
        imu["gyro_dps"] = groups[:, 4:7] * self.dps_per_lsb
        return imu


def read_header(file: BinaryIO, path: str) -> tuple[int, bytes]:
    """Check the magic and read the ``#`` header lines; return (data start, header bytes).

    The header ends after the ``#End Of ASCII Header`` line or before the first line that
    does not start with ``#``.
    """
    first = file.readline(len(MAGIC))
    if not first:
        raise FormatError("empty file: not an AEDAT 2.0 recording", path=path, offset=0)
    if first != MAGIC:
        raise FormatError(f"first line is {first!r}, expected {MAGIC!r}", path=path, offset=0)
    lines = [first]
    while True:
        start = file.tell()
        if file.read(1) != b"#":
            return start, b"".join(lines)
        file.seek(start)
        line = file.readline(MAX_HEADER_BYTES)
        lines.append(line)
        if line.startswith(END_OF_HEADER):
            return file.tell(), b"".join(lines)
        if start > MAX_HEADER_BYTES:
            raise FormatError(
                "header longer than 16 MiB: not an AEDAT 2.0 file", path=path, offset=start
            )


class Aedat2Reader(FileReader):
    """An AEDAT 2.0 file as a :class:`~davis_io.types.PacketSource`.

    Yields one Packet per 262,144 records. The chip (and so the array size used to flip y to the
    top-left origin) comes from the ``# AEChip:`` header line unless ``camera`` is given; the
    IMU full scales from the header's preference dump, else jAER's defaults (±8 g, ±1000 °/s).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        camera: str | None = None,
        accel_full_scale_g: int | None = None,
        gyro_full_scale_dps: int | None = None,
        global_shutter: bool = True,
    ):
        """Open ``path`` and read its header.

        Raises:
            FormatError: empty file, wrong magic, or a chip whose size is unknown.
        """
        super().__init__(path)
        try:
            self._data_start, header = read_header(self._file, str(self.path))
            chip = re.search(rb"# AEChip: *(\S+)", header)
            chip_name = camera or (chip.group(1).decode("ascii", "replace") if chip else "")
            model, width, height = identify_chip(chip_name)
            if not width:
                raise FormatError(
                    f"chip {chip_name or '(none in header)'!r} is not a known DAVIS, so the array "
                    f"size is unknown; pass camera= one of {sorted(SENSOR_SIZES)}",
                    path=str(self.path),
                )
        except BaseException:
            self._file.close()
            raise
        accel = accel_full_scale_g or _header_scale(_ACCEL_KEY, header, DEFAULT_ACCEL_FULL_SCALE_G)
        gyro = gyro_full_scale_dps or _header_scale(_GYRO_KEY, header, DEFAULT_GYRO_FULL_SCALE_DPS)
        self._decoder_args = (
            width,
            height,
            accel,
            gyro,
            global_shutter,
            2 if model == "DAVIS240" else 1,
        )
        color = ColorFilter.RGGB if "color" in chip_name.lower() else ColorFilter.MONO
        self.info = SourceInfo(
            camera=model,
            serial="",
            width=width,
            height=height,
            color_filter=color,
            origin=f"replay:{self.path.name}",
            extra={
                "format": "AEDAT 2.0",
                "chip": chip_name,
                "accel_full_scale_g": accel,
                "gyro_full_scale_dps": gyro,
            },
        )

    def __iter__(self) -> Iterator[Packet]:
        decoder = Aedat2Decoder(*self._decoder_args)
        self._file.seek(self._data_start)
        offset = self._data_start
        while True:
            data = self._file.read(RECORDS_PER_PACKET * RECORD_DTYPE.itemsize)
            if not data:
                return
            complete = len(data) - len(data) % RECORD_DTYPE.itemsize
            packet = decoder.decode(np.frombuffer(data, dtype=RECORD_DTYPE, count=complete // 8))
            if complete < len(data):
                packet.truncated_at = offset + complete
                packet.notes.append(
                    warn_note(
                        f"{self.path}: file truncated at byte offset {offset + complete}: "
                        f"{len(data) - complete} bytes of an incomplete record ignored"
                    )
                )
            yield packet
            offset += len(data)


def _header_scale(pattern: re.Pattern, header: bytes, default: int) -> int:
    match = pattern.search(header)
    return int(match.group(1)) if match else default
