"""Streaming AEDAT 4.0 reader: one Packet per file packet, data table time-range reads."""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import zstandard

from davis_io.aedat.aedat4_header import (
    MAGIC,
    DataTableEntry,
    StreamDescription,
    decompress,
    packet_decompressor,
    parse_data_table,
    parse_info_node,
    parse_io_header,
)
from davis_io.aedat.aedat4_streams import (
    FRAME_BIT_DEPTH_KEY,
    decode_events,
    decode_frame,
    decode_imu,
    decode_triggers,
)
from davis_io.aedat.report import FileReader, warn_note
from davis_io.colorfilter import DEVICE_COLOR_FILTERS
from davis_io.errors import FormatError
from davis_io.types import ColorFilter, Packet, SourceInfo

__all__ = ["Aedat4Reader", "clip_packet"]

_PACKET_HEADER = struct.Struct("<ii")
_CODEC_ERRORS = (RuntimeError, ValueError, zstandard.ZstdError)
_FRAME_SLACK_US = 10_000_000  # a frame's table stamp (DV: exposure midpoint) is at most this late


class Aedat4Reader(FileReader):
    """An AEDAT 4.0 file as a :class:`~davis_io.types.PacketSource`.

    The header is read on construction (so ``info`` is known at once); iteration walks the
    packets from the start each time, reading one packet at a time. Each packet is
    decompressed into a new buffer (see :func:`packet_decompressor`) that its events keep as
    their memory; frames, IMU samples and triggers are copied out of it.

    Attributes:
        info: camera, resolution and file facts (``extra``: format, compression, streams).
        streams: the infoNode's streams by stream id.
        data_table: the FileDataTable rows, or None when the file has none.
    """

    def __init__(self, path: str | Path, native_lz4: bool | None = None):
        """Open ``path`` and read its header and data table.

        Args:
            path: the recording.
            native_lz4: LZ4 packets through the system's liblz4 (True), python-lz4 (False),
                or liblz4 when the system has it (None).

        Raises:
            FormatError: empty file, wrong magic, or a malformed header.
            RuntimeError: ``native_lz4`` is True and the system has no usable liblz4.
        """
        super().__init__(path)
        self._native_lz4 = native_lz4
        self._read_buffer = bytearray()
        try:
            self._read_header()
        except BaseException:
            self._file.close()
            raise

    @property
    def time_range(self) -> tuple[int, int] | None:
        """First and last element time in µs from the data table, or None if unknown."""
        stamped = [e for e in self.data_table or [] if e.timestamp_start or e.timestamp_end]
        if not stamped:
            return None
        return min(e.timestamp_start for e in stamped), max(e.timestamp_end for e in stamped)

    def __iter__(self) -> Iterator[Packet]:
        notes, truncated = list(self._header_notes), False
        for item in self._walk():
            if isinstance(item, str):
                notes.append(item)
            elif isinstance(item, Packet):
                truncated = True
                yield _with_notes(item, notes)
            else:
                yield _with_notes(self._decode(*item), notes)
        if self._cut_at is not None and not truncated:
            yield Packet(notes=notes, truncated_at=self._cut_at)
        elif notes:
            yield Packet(notes=notes)

    def _walk(self) -> Iterator[tuple[int, int, int, memoryview] | str | Packet]:
        """Read packets in file order: their payloads, notes, and where a truncated file stops.

        Yields ``(index, offset, stream id, payload)``, a note string, or the empty packet that
        ends a truncated file (its ``truncated_at``). Each payload is a view of a buffer that
        the next packet's payload overwrites. Packets of unknown streams are skipped here, with
        one note per stream.
        """
        offset, index, skipped = self._data_start, 0, set()
        while offset < self._data_end:
            header = self._read_at(offset, _PACKET_HEADER.size)
            if len(header) < _PACKET_HEADER.size:
                yield _cut(
                    offset,
                    f"{self.path}: file truncated at byte offset {offset}: "
                    "incomplete packet header; later data is lost",
                )
                return
            stream_id, size = _PACKET_HEADER.unpack(header)
            if size < 0:
                raise FormatError(
                    f"packet {index} declares a negative size {size}",
                    path=str(self.path),
                    offset=offset,
                )
            payload = self._read_payload(min(size, self._data_end - offset - _PACKET_HEADER.size))
            if len(payload) < size:
                yield _cut(
                    offset,
                    f"{self.path}: file truncated at byte offset {offset}: packet {index} needs "
                    f"{size} bytes, {len(payload)} remain; later data is lost",
                )
                return
            type_id = self._type_of(stream_id)
            if type_id in _DECODERS:
                yield index, offset, stream_id, payload
            elif stream_id not in skipped:
                skipped.add(stream_id)
                yield self._skip_note(index, offset, stream_id, type_id)
            offset, index = offset + _PACKET_HEADER.size + size, index + 1

    def read_range(self, start_us: int, end_us: int) -> Iterator[Packet]:
        """Yield the records with ``start_us <= t < end_us``, reading only the packets needed.

        Uses the data table to seek; frames are selected by exposure start (a table stamp never
        precedes it). Without a data table, or one without timestamps, every packet is read.
        """
        entries = self.data_table if self.time_range is not None else None
        if entries is None:
            for packet in self:
                yield clip_packet(packet, start_us, end_us)
            return
        for index, entry in enumerate(entries):
            type_id = self._type_of(entry.stream_id)
            slack = _FRAME_SLACK_US if type_id == "FRME" else 0
            if (
                type_id not in _DECODERS
                or entry.timestamp_end < start_us
                or entry.timestamp_start >= end_us + slack
            ):
                continue
            payload_offset = self._payload_offset(index, entry)
            payload = self._read_at(payload_offset, entry.size)
            packet = self._decode(index, payload_offset - 8, entry.stream_id, payload)
            yield clip_packet(packet, start_us, end_us)

    # ---- internals ---------------------------------------------------------------------------

    def _read_payload(self, size: int) -> memoryview:
        """The next ``size`` bytes of the file (fewer at its end) in the reused read buffer."""
        if len(self._read_buffer) < size:
            self._read_buffer = bytearray(size)
        view = memoryview(self._read_buffer)[:size]
        return view[: self._file.readinto(view)]

    def _read_at(self, offset: int, size: int) -> bytes:
        self._file.seek(offset)
        return self._file.read(size)

    def _read_header(self) -> None:
        path = str(self.path)
        file_size = self.path.stat().st_size
        magic = self._file.read(len(MAGIC))
        if not magic:
            raise FormatError("empty file: not an AEDAT 4.0 recording", path=path, offset=0)
        if magic != MAGIC:
            raise FormatError(f"first bytes are {magic!r}, expected {MAGIC!r}", path=path, offset=0)
        prefix = self._file.read(4)
        length = struct.unpack("<I", prefix)[0] if len(prefix) == 4 else file_size
        if length > file_size - len(MAGIC) - 4:
            raise FormatError(
                "file ends inside the IOHeader: truncated header", path=path, offset=len(MAGIC)
            )
        try:
            header = parse_io_header(prefix + self._file.read(length))
            self.streams = parse_info_node(header.info_node)
        except FormatError as error:
            raise FormatError(f"bad IOHeader: {error}", path=path, offset=len(MAGIC)) from None
        self.compression = header.compression
        self._decompress = packet_decompressor(self.compression, self._native_lz4)
        self._data_start = len(MAGIC) + 4 + length
        self._data_end, self._header_notes, self._cut_at = file_size, [], None
        self.data_table: list[DataTableEntry] | None = None
        position = header.data_table_position
        if position > file_size:
            self._cut_at = file_size
            self._header_notes.append(
                warn_note(
                    f"{path}: data table position {position} lies beyond the end of the file "
                    f"({file_size} bytes): file truncated; reading packets up to the end"
                )
            )
        elif position >= self._data_start:
            self._data_end = position
            self.data_table = self._load_data_table(position)
        self.info = self._source_info()

    def _load_data_table(self, position: int) -> list[DataTableEntry] | None:
        blob = self._read_at(position, self.path.stat().st_size - position)
        try:
            return parse_data_table(decompress(self.compression, blob))
        except (FormatError, *_CODEC_ERRORS) as error:
            self._header_notes.append(
                warn_note(
                    f"{self.path}: data table at byte offset {position} is unreadable ({error}); "
                    "reading without it"
                )
            )
            return None

    def _source_info(self) -> SourceInfo:
        by_type = {s.type_identifier: s for s in self.streams.values()}
        sized = by_type.get("EVTS") or by_type.get("FRME") or StreamDescription(-1, "", "")
        source = next((s.source for s in self.streams.values() if s.source), "")
        camera, _, serial = source.rpartition("_") if "_" in source else (source, "", "")
        extra = {
            "format": "AEDAT 4.0",
            "compression": self.compression.name,
            "streams": [s.name or s.type_identifier for s in self.streams.values()],
            "source": source,
            "data_table": self.data_table is not None,
        }
        ts_offset = sized.info.get("tsOffset")
        if ts_offset and ts_offset.lstrip("-").isdigit():
            extra["ts_offset_us"] = int(ts_offset)
        return SourceInfo(
            camera=camera,
            serial=serial,
            width=sized.width,
            height=sized.height,
            color_filter=self._stated_color_filter(by_type.get("FRME")),
            origin=f"replay:{self.path.name}",
            extra=extra,
        )

    def _stated_color_filter(self, frames: StreamDescription | None) -> ColorFilter:
        """The frame stream's ``colorFilter`` attribute, read as the APS register value.

        DV's numbering of it is not documented; the register's is the likeliest. Absent (DV
        writes none for mono sensors), the sensor is taken as mono.
        """
        stated = frames.info.get("colorFilter", "0") if frames is not None else "0"
        if not stated.isdigit() or int(stated) >= len(DEVICE_COLOR_FILTERS):
            raise FormatError(
                f"frame stream attribute colorFilter = {stated!r} is not a colour filter "
                f"(0-{len(DEVICE_COLOR_FILTERS) - 1})",
                path=str(self.path),
            )
        return DEVICE_COLOR_FILTERS[int(stated)]

    def _type_of(self, stream_id: int) -> str:
        stream = self.streams.get(stream_id)
        return stream.type_identifier if stream else ""

    def _payload_offset(self, index: int, entry: DataTableEntry) -> int:
        """Accept both ByteOffset conventions: payload (DV) or packet header (jAER)."""
        expected = _PACKET_HEADER.pack(entry.stream_id, entry.size)
        if entry.byte_offset >= 8 and self._read_at(entry.byte_offset - 8, 8) == expected:
            return entry.byte_offset
        if self._read_at(entry.byte_offset, 8) == expected:
            return entry.byte_offset + 8
        raise FormatError(
            f"data table row {index} points at no packet of stream {entry.stream_id}",
            path=str(self.path),
            offset=entry.byte_offset,
        )

    def _decode(self, index: int, offset: int, stream_id: int, payload: bytes) -> Packet:
        """Decompress and decode one packet of a known stream type into arrays of its own."""
        stream = self.streams[stream_id]
        type_id = stream.type_identifier
        try:
            return _DECODERS[type_id](stream, self._decompress(payload))
        except (FormatError, *_CODEC_ERRORS) as error:
            message = error if isinstance(error, FormatError) else f"cannot decompress: {error}"
            raise FormatError(
                f"packet {index} (stream {stream_id}, {type_id}): {message}",
                path=str(self.path),
                offset=offset,
            ) from None

    def _skip_note(self, index: int, offset: int, stream_id: int, type_id: str) -> str:
        kind = f"type {type_id!r}" if type_id else "not described in the infoNode"
        return warn_note(
            f"{self.path}: packet {index} at byte offset {offset}: stream {stream_id} "
            f"({kind}) is not a known stream type; its packets are skipped"
        )


def _frame_packet(stream: StreamDescription, buf: bytes) -> Packet:
    """One frame; 16-bit pixels are shifted back by the stream's ``bitDepth`` (default 16)."""
    depth = stream.info.get(FRAME_BIT_DEPTH_KEY, "16")
    bit_depth = int(depth) if depth.isdigit() and 1 <= int(depth) <= 16 else 16
    return Packet(frames=[decode_frame(buf, bit_depth)])


def _cut(offset: int, message: str) -> Packet:
    """The packet that ends a truncated file: no records, the note, where the data stops."""
    return Packet(notes=[warn_note(message)], truncated_at=offset)


def _with_notes(packet: Packet, notes: list[str]) -> Packet:
    """Put the notes gathered so far in front of the packet's own; empty ``notes``."""
    packet.notes[:0] = notes
    notes.clear()
    return packet


def clip_packet(packet: Packet, start_us: int, end_us: int) -> Packet:
    """Keep the records with ``start_us <= t < end_us`` (frames by exposure start)."""

    def inside(times: np.ndarray) -> np.ndarray:
        return (times >= start_us) & (times < end_us)

    frames = [f for f in packet.frames if start_us <= f.exposure_start_us < end_us]
    return Packet(
        events=packet.events[inside(packet.events["t"])],
        frames=frames,
        imu=packet.imu[inside(packet.imu["t"])],
        triggers=packet.triggers[inside(packet.triggers["t"])],
        dropped_events=packet.dropped_events,
        notes=packet.notes,
    )


_DECODERS = {
    "EVTS": lambda stream, buf: Packet(events=decode_events(buf)),
    "FRME": _frame_packet,
    "IMUS": lambda stream, buf: Packet(imu=decode_imu(buf)),
    "TRIG": lambda stream, buf: Packet(triggers=decode_triggers(buf)),
}
