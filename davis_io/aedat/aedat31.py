"""Streaming AEDAT 3.1 (cAER) reader: polarity, frame, IMU6 and special event packets."""

from __future__ import annotations

import re
import struct
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

import numpy as np

from davis_io.aedat.report import FileReader, warn_note
from davis_io.chips import identify_chip
from davis_io.errors import FormatError
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, SourceInfo

__all__ = ["SPECIAL_TO_TRIGGER", "Aedat31Reader", "decode_packet"]

MAGIC = b"#!AER-DAT3.1\r\n"
END_OF_HEADER = b"#!END-HEADER\r\n"
MAX_HEADER_BYTES = 1 << 20

_PACKET_HEADER = struct.Struct("<hhiiiiii")
_POLARITY = np.dtype([("data", "<u4"), ("t", "<i4")])
_IMU6 = np.dtype(
    [
        ("info", "<u4"),
        ("t", "<i4"),
        ("acc", "<f4", (3,)),
        ("gyro", "<f4", (3,)),
        ("temperature", "<f4"),
    ]
)
_FRAME_HEADER = struct.Struct("<Iiiiiiiii")
_EVENT_SIZES = {0: 8, 1: 8, 3: 36}  # fixed event size per type; frames vary

SPECIAL_TO_TRIGGER = {1: 0, 2: 1, 3: 2, 4: 3, 12: 4, 13: 5, 14: 6, 15: 7, 16: 8, 17: 9}
"""libcaer special event type -> :class:`~davis_io.types.TriggerKind` (others are dropped)."""


class Aedat31Reader(FileReader):
    """An AEDAT 3.1 file as a :class:`~davis_io.types.PacketSource`, one Packet per file packet.

    Frames come back as 10-bit ``uint16`` (the file's 16-bit normalized pixels shifted right by
    6), colour frames as ``(H, W, C)`` RGB(A).
    """

    def __init__(self, path: str | Path):
        """Open ``path`` and read its header.

        Raises:
            FormatError: empty file, wrong magic or no end-of-header line.
        """
        super().__init__(path)
        try:
            self._file_size = self.path.stat().st_size
            self._data_start, sources = _read_header(self._file, str(self.path))
        except BaseException:
            self._file.close()
            raise
        model, width, height = identify_chip(sources.get(1, next(iter(sources.values()), "")))
        self.info = SourceInfo(
            camera=model,
            serial="",
            width=width,
            height=height,
            origin=f"replay:{self.path.name}",
            extra={"format": "AEDAT 3.1", "sources": sources},
        )

    def __iter__(self) -> Iterator[Packet]:
        self._file.seek(self._data_start)
        offset, index, skipped = self._data_start, 0, set()
        while True:
            header = self._file.read(_PACKET_HEADER.size)
            if len(header) < _PACKET_HEADER.size:
                if header:
                    yield Packet(
                        truncated_at=offset,
                        notes=[
                            warn_note(
                                f"{self.path}: file truncated at byte offset {offset}: incomplete "
                                f"header of packet {index}; later data is lost"
                            )
                        ],
                    )
                return
            fields = _check_header(header, offset, index, str(self.path))
            size = fields[2] * fields[5]
            payload = self._file.read(min(size, self._file_size - offset - len(header)))
            notes = []
            if len(payload) < size:
                notes.append(
                    warn_note(
                        f"{self.path}: file truncated at byte offset {offset}: packet {index} "
                        f"needs {size} payload bytes, {len(payload)} remain; its complete events "
                        "are kept"
                    )
                )
            try:
                packet = decode_packet(fields, payload, notes)
            except FormatError as error:
                raise FormatError(
                    f"packet {index}: {error}", path=str(self.path), offset=offset
                ) from None
            if fields[0] not in _DECODERS and fields[0] not in skipped:
                skipped.add(fields[0])
                packet.notes.append(
                    warn_note(
                        f"{self.path}: packet {index} at byte offset {offset}: event type "
                        f"{fields[0]} is not read (polarity, frame, IMU6, special are); skipped"
                    )
                )
            if notes:
                packet.truncated_at = offset
            yield packet
            if notes:
                return
            offset, index = offset + len(header) + size, index + 1


def _read_header(file: BinaryIO, path: str) -> tuple[int, dict[int, str]]:
    """Check the magic, read header lines up to ``#!END-HEADER``; return data start, sources."""
    first = file.readline(len(MAGIC))
    if not first:
        raise FormatError("empty file: not an AEDAT 3.1 recording", path=path, offset=0)
    if first != MAGIC:
        raise FormatError(f"first line is {first!r}, expected {MAGIC!r}", path=path, offset=0)
    sources = {}
    while True:
        offset = file.tell()
        line = file.readline(MAX_HEADER_BYTES)
        if line == END_OF_HEADER:
            return file.tell(), sources
        if not line.startswith(b"#") or not line.endswith(b"\n") or offset > MAX_HEADER_BYTES:
            raise FormatError(
                "header ends without the '#!END-HEADER' line", path=path, offset=offset
            )
        match = re.match(rb"#Source (\d+): (.*?)\r?\n", line)
        if match:
            sources[int(match.group(1))] = match.group(2).decode("utf-8", "replace")


def _check_header(header: bytes, offset: int, index: int, path: str) -> tuple:
    fields = _PACKET_HEADER.unpack(header)
    event_type, _, size, ts_offset, overflow, capacity, number, valid = fields
    fixed = _EVENT_SIZES.get(event_type)
    bad = (
        size <= 0
        or capacity < 0
        or not 0 <= valid <= number <= capacity
        or overflow < 0
        or (fixed is not None and size != fixed)
        or (event_type == 2 and size < 36)
    )
    if bad:
        raise FormatError(
            f"packet {index} header is inconsistent (type {event_type}, event size {size}, "
            f"capacity {capacity}, number {number}, valid {valid}, overflow {overflow})",
            path=path,
            offset=offset,
        )
    return fields


def decode_packet(fields: tuple, payload: bytes, notes: list[str]) -> Packet:
    """Decode the complete events of one packet payload (pure; unknown types give no records).

    Args:
        fields: the 8 packet header values (type, source, size, ts offset, overflow, capacity,
            number, valid).
        payload: the payload bytes (may be short when the file is truncated).
        notes: notes to carry on the returned packet.
    """
    decoder = _DECODERS.get(fields[0])
    count = min(fields[5], len(payload) // fields[2])
    packet = decoder(payload, count, fields[2], fields[4] << 31) if decoder else Packet()
    packet.notes[:0] = notes
    return packet


def _polarity(payload: bytes, count: int, size: int, base: int) -> Packet:
    raw = np.frombuffer(payload, dtype=_POLARITY, count=count)
    raw = raw[(raw["data"] & 1) == 1]
    events = np.empty(len(raw), dtype=EVENT_DTYPE)
    events["t"] = base + raw["t"].astype(np.int64)
    events["x"] = raw["data"] >> 17
    events["y"] = (raw["data"] >> 2) & 0x7FFF
    events["p"] = np.where(raw["data"] & 2, 1, -1)
    return Packet(events=events)


def _special(payload: bytes, count: int, size: int, base: int) -> Packet:
    raw = np.frombuffer(payload, dtype=_POLARITY, count=count)
    raw = raw[(raw["data"] & 1) == 1]
    kinds = (raw["data"] >> 1) & 0x7F
    known = np.isin(kinds, list(SPECIAL_TO_TRIGGER))
    triggers = np.empty(int(known.sum()), dtype=TRIGGER_DTYPE)
    triggers["t"] = base + raw["t"][known].astype(np.int64)
    lookup = np.zeros(128, dtype=np.int8)
    lookup[list(SPECIAL_TO_TRIGGER)] = list(SPECIAL_TO_TRIGGER.values())
    triggers["kind"] = lookup[kinds[known]]
    return Packet(triggers=triggers)


def _imu6(payload: bytes, count: int, size: int, base: int) -> Packet:
    raw = np.frombuffer(payload, dtype=_IMU6, count=count)
    raw = raw[(raw["info"] & 1) == 1]
    imu = np.empty(len(raw), dtype=IMU_DTYPE)
    imu["t"] = base + raw["t"].astype(np.int64)
    imu["acc_g"] = raw["acc"]
    imu["gyro_dps"] = raw["gyro"]
    imu["temperature_c"] = raw["temperature"]
    return Packet(imu=imu)


def _frames(payload: bytes, count: int, size: int, base: int) -> Packet:
    frames = []
    for start in range(0, count * size, size):
        info, sof, eof, soe, eoe, width, height, x, y = _FRAME_HEADER.unpack_from(payload, start)
        channels = (info >> 1) & 7
        pixels = width * height * channels
        if not info & 1:
            continue
        if channels not in (1, 3, 4) or width < 0 or height < 0 or 36 + 2 * pixels > size:
            raise FormatError(
                f"frame event at payload byte {start} has {width} x {height} x "
                f"{channels} pixels, which do not fit its {size}-byte event"
            )
        image = np.frombuffer(payload, dtype="<u2", count=pixels, offset=start + 36) >> 6
        shape = (height, width, channels) if channels > 1 else (height, width)
        frames.append(
            Frame(
                image=image.astype(np.uint16).reshape(shape),
                exposure_start_us=base + soe,
                exposure_end_us=base + eoe,
                readout_start_us=base + sof,
                readout_end_us=base + eof,
                bit_depth=10,
                position=(x, y),
            )
        )
    return Packet(frames=frames)


_DECODERS = {0: _special, 1: _polarity, 2: _frames, 3: _imu6}
