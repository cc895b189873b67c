"""AEDAT 4.0 file framing: IOHeader, infoNode XML, FileDataTable and packet compression."""

from __future__ import annotations

import enum
import functools
import xml.etree.ElementTree as ElementTree
from collections.abc import Callable
from dataclasses import dataclass, field

import lz4.frame
import numpy as np
import zstandard

from davis_io.aedat.aedat4_streams import STREAM_TYPES
from davis_io.aedat.flatbuf import (
    FlatBufferError,
    Scalar,
    StringField,
    StructField,
    TablesField,
    build_buffer,
    root_table,
)
from davis_io.aedat.lz4_frame import FrameDecompressor, decompress_frame

__all__ = [
    "MAGIC",
    "Compression",
    "DataTableEntry",
    "IOHeader",
    "StreamDescription",
    "build_data_table",
    "build_info_node",
    "build_io_header",
    "compress",
    "decompress",
    "packet_decompressor",
    "parse_data_table",
    "parse_info_node",
    "parse_io_header",
]

MAGIC = b"#!AER-DAT4.0\r\n"
"""The first 14 bytes of every AEDAT 4.0 file."""


class Compression(enum.IntEnum):
    """Packet compression of an AEDAT 4.0 file (IOHeader field 0)."""

    NONE = 0
    LZ4 = 1
    LZ4_HIGH = 2
    ZSTD = 3
    ZSTD_HIGH = 4


@dataclass(frozen=True)
class IOHeader:
    """The file header: compression, absolute data table position (-1 = none), infoNode XML."""

    compression: Compression
    data_table_position: int
    info_node: str


@dataclass(frozen=True)
class StreamDescription:
    """One stream of the infoNode: id, type identifier (``EVTS``...), output name and info."""

    stream_id: int
    type_identifier: str
    name: str
    width: int = 0
    height: int = 0
    source: str = ""
    info: dict = field(default_factory=dict)


@dataclass(frozen=True)
class DataTableEntry:
    """One FileDataTable row: payload byte offset, stream, stored size, element count, times."""

    byte_offset: int
    stream_id: int
    size: int
    num_elements: int
    timestamp_start: int
    timestamp_end: int


def decompress(compression: Compression, data: bytes) -> bytes:
    """Decompress one packet payload (one complete LZ4 or Zstandard frame).

    Raises:
        RuntimeError, ValueError, zstandard.ZstdError: from the codec, for the caller to wrap.
    """
    if compression in (Compression.LZ4, Compression.LZ4_HIGH):
        return decompress_frame(data)
    if compression in (Compression.ZSTD, Compression.ZSTD_HIGH):
        return zstandard.ZstdDecompressor().decompressobj().decompress(data)
    return data


def packet_decompressor(
    compression: Compression, native_lz4: bool | None = None
) -> Callable[[bytes], bytes | np.ndarray]:
    """A :func:`decompress` for one reader's packets, decoded one after the other.

    Every result is new memory that the decoded records may keep as views, whatever the payload
    was: for LZ4 a writable uint8 array (see :class:`~davis_io.aedat.lz4_frame.FrameDecompressor`,
    which ``native_lz4`` is passed to), for Zstandard bytes, uncompressed a copy.
    """
    if compression in (Compression.LZ4, Compression.LZ4_HIGH):
        return FrameDecompressor(native_lz4).decompress
    if compression is Compression.NONE:
        return bytearray  # a copy: the payload may be a view of the reader's reused buffer
    return functools.partial(decompress, compression)


def compress(compression: Compression, data: bytes) -> bytes:
    """Compress one packet payload the way DV does (LZ4 frame with 64 KiB linked blocks)."""
    if compression in (Compression.LZ4, Compression.LZ4_HIGH):
        level = 9 if compression is Compression.LZ4_HIGH else 0
        return lz4.frame.compress(
            data,
            compression_level=level,
            store_size=False,
            block_size=lz4.frame.BLOCKSIZE_MAX64KB,
            block_linked=True,
        )
    if compression in (Compression.ZSTD, Compression.ZSTD_HIGH):
        level = 19 if compression is Compression.ZSTD_HIGH else 3
        return zstandard.ZstdCompressor(level=level).compress(data)
    return data


def parse_io_header(buf: bytes) -> IOHeader:
    """Parse the size-prefixed IOHeader FlatBuffer.

    Raises:
        FlatBufferError: malformed buffer or unknown compression.
    """
    table = root_table(buf, b"IOHE")
    code = int(table.scalar(0, "<i", 0))
    if code not in Compression._value2member_map_:
        raise FlatBufferError(f"unknown compression code {code} in the IOHeader (expected 0-4)")
    return IOHeader(Compression(code), int(table.scalar(1, "<q", -1)), table.string(2) or "")


def build_io_header(header: IOHeader) -> bytes:
    """Build the IOHeader; every field is written so the size never depends on the values."""
    return build_buffer(
        b"IOHE",
        [
            Scalar(0, "<i", int(header.compression)),
            Scalar(1, "<q", header.data_table_position),
            StringField(2, header.info_node),
        ],
    )


def parse_info_node(xml_text: str) -> dict[int, StreamDescription]:
    """Read the streams of the infoNode XML, keyed by stream id.

    Raises:
        FlatBufferError: the XML does not parse or a stream node name is not an integer.
    """
    try:
        root = ElementTree.fromstring(xml_text)
    except ElementTree.ParseError as error:
        raise FlatBufferError(f"infoNode XML does not parse ({error})") from None
    streams = {}
    out_info = root.find("node[@name='outInfo']")
    for node in [] if out_info is None else out_info.findall("node"):
        try:
            stream_id = int(node.get("name", ""))
        except ValueError:
            raise FlatBufferError(
                f"stream node name {node.get('name')!r} is not an integer"
            ) from None
        attrs = _attrs(node)
        info_node = node.find("node[@name='info']")
        info = _attrs(info_node) if info_node is not None else {}
        streams[stream_id] = StreamDescription(
            stream_id,
            attrs.get("typeIdentifier", ""),
            attrs.get("originalOutputName", ""),
            _int(info.get("sizeX")),
            _int(info.get("sizeY")),
            info.get("source", ""),
            info,
        )
    return streams


def _attrs(node: ElementTree.Element) -> dict[str, str]:
    return {attr.get("key", ""): (attr.text or "") for attr in node.findall("attr")}


def _int(text: str | None) -> int:
    try:
        return int(text) if text else 0
    except ValueError:
        return 0


def build_info_node(streams: list[StreamDescription], compression: Compression) -> str:
    """Write the infoNode XML the way DV's recorder does (``<dv version="2.0">``)."""
    base = "/mainloop/Recorder/outInfo/"
    lines = ['<dv version="2.0">', f'    <node name="outInfo" path="{base}">']
    for stream in streams:
        path = f"{base}{stream.stream_id}/"
        lines.append(f'        <node name="{stream.stream_id}" path="{path}">')
        for key, value in (
            ("compression", compression.name),
            ("originalModuleName", "seecap"),
            ("originalOutputName", stream.name),
            ("typeDescription", STREAM_TYPES[stream.type_identifier][1]),
            ("typeIdentifier", stream.type_identifier),
        ):
            lines.append(f'            <attr key="{key}" type="string">{_escape(value)}</attr>')
        lines.append(f'            <node name="info" path="{path}info/">')
        for key, (kind, value) in _info_attrs(stream).items():
            lines.append(f'                <attr key="{key}" type="{kind}">{_escape(value)}</attr>')
        lines += ["            </node>", "        </node>"]
    lines += ["    </node>", "</dv>", ""]
    return "\n".join(lines)


def _info_attrs(stream: StreamDescription) -> dict[str, tuple[str, str]]:
    attrs = {}
    if stream.width and stream.height:
        attrs["sizeX"] = ("int", str(stream.width))
        attrs["sizeY"] = ("int", str(stream.height))
    attrs["source"] = ("string", stream.source)
    for key, value in stream.info.items():
        attrs[key] = ("int", str(value)) if isinstance(value, int) else ("string", str(value))
    return attrs


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def parse_data_table(buf: bytes) -> list[DataTableEntry]:
    """Parse the decompressed ``FTAB`` FileDataTable (absent fields read as 0).

    Raises:
        FlatBufferError: malformed buffer.
    """
    columns = root_table(buf, b"FTAB").table_columns(0, _DATA_TABLE_COLUMNS)
    return [DataTableEntry(*row) for row in zip(*(c.tolist() for c in columns), strict=True)]


_DATA_TABLE_COLUMNS = [
    (0, 0, "<i8"),
    (1, 0, "<i4"),
    (1, 4, "<i4"),
    (2, 0, "<i8"),
    (3, 0, "<i8"),
    (4, 0, "<i8"),
]
"""FileDataTable row fields in :class:`DataTableEntry` order: (slot, offset in field, dtype)."""


def build_data_table(entries: list[DataTableEntry]) -> bytes:
    """Build the ``FTAB`` FileDataTable FlatBuffer (uncompressed)."""
    tables = [
        [
            Scalar(0, "<q", entry.byte_offset),
            StructField(1, "<ii", (entry.stream_id, entry.size)),
            Scalar(2, "<q", entry.num_elements),
            Scalar(3, "<q", entry.timestamp_start),
            Scalar(4, "<q", entry.timestamp_end),
        ]
        for entry in entries
    ]
    return build_buffer(b"FTAB", [TablesField(0, tables)])
