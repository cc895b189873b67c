"""A minimal FlatBuffers reader and forward builder for the small AEDAT 4.0 schemas.

Only what AEDAT 4.0 needs: tables with scalar fields, strings, inline structs, vectors of
structs or bytes and vectors of tables, in size-prefixed buffers with a 4-character file
identifier. Every read is bounds-checked and raises :class:`FlatBufferError`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from davis_io.errors import FormatError

__all__ = [
    "FlatBufferError",
    "FlatTable",
    "Scalar",
    "StringField",
    "StructField",
    "TablesField",
    "VectorField",
    "build_buffer",
    "root_table",
]

_U32 = struct.Struct("<I")
_I32 = struct.Struct("<i")
_U16 = struct.Struct("<H")


class FlatBufferError(FormatError):
    """A FlatBuffer is malformed (an offset or length points outside the buffer)."""


class FlatTable:
    """One table inside a FlatBuffer; fields are read by vtable slot number."""

    def __init__(self, buf: bytes, pos: int):
        """Locate the table at ``pos`` of ``buf`` and its vtable.

        Raises:
            FlatBufferError: the table or its vtable lies outside the buffer.
        """
        self.buf = buf
        self.pos = pos
        vtable = pos - _read(buf, _I32, pos, "table")
        self._vtable = vtable
        self._vtable_size = _read(buf, _U16, vtable, "vtable")
        _check(buf, vtable, self._vtable_size, "vtable")

    def field_pos(self, slot: int) -> int | None:
        """Absolute position of a field's inline value, or None when the field is absent."""
        entry = 4 + 2 * slot
        if entry + 2 > self._vtable_size:
            return None
        offset = _U16.unpack_from(self.buf, self._vtable + entry)[0]
        return self.pos + offset if offset else None

    def scalar(self, slot: int, fmt: str, default: int | float = 0) -> int | float:
        """Read a scalar field (``struct`` format such as ``"<q"``), or ``default`` if absent."""
        pos = self.field_pos(slot)
        if pos is None:
            return default
        codec = struct.Struct(fmt)
        _check(self.buf, pos, codec.size, f"field {slot}")
        return codec.unpack_from(self.buf, pos)[0]

    def struct_at(self, slot: int, fmt: str) -> tuple | None:
        """Read an inline struct field as a tuple, or None if absent."""
        pos = self.field_pos(slot)
        if pos is None:
            return None
        codec = struct.Struct(fmt)
        _check(self.buf, pos, codec.size, f"struct field {slot}")
        return codec.unpack_from(self.buf, pos)

    def vector(self, slot: int, element_size: int) -> tuple[int, int]:
        """Return ``(start, count)`` of a vector field's elements; ``(0, 0)`` if absent."""
        target = self._target(slot)
        if target is None:
            return 0, 0
        count = _read(self.buf, _U32, target, f"vector {slot} length")
        _check(self.buf, target + 4, count * element_size, f"vector {slot}")
        return target + 4, count

    def string(self, slot: int) -> str | None:
        """Read a UTF-8 string field, or None if absent."""
        start, length = self.vector(slot, 1)
        if start == 0:
            return None
        try:
            return bytes(self.buf[start : start + length]).decode("utf-8")
        except UnicodeDecodeError as error:
            raise FlatBufferError(f"string field {slot} is not UTF-8 ({error})") from None

    def tables(self, slot: int) -> list[FlatTable]:
        """Read a vector of tables."""
        start, count = self.vector(slot, 4)
        return [
            FlatTable(self.buf, start + 4 * i + _U32.unpack_from(self.buf, start + 4 * i)[0])
            for i in range(count)
        ]

    def table_columns(self, slot: int, columns: list[tuple[int, int, str]]) -> list[np.ndarray]:
        """Read fields of every table in a vector of tables at once, one array per column.

        Args:
            slot: the vector-of-tables field.
            columns: ``(field slot, byte offset inside the field, numpy dtype)`` per column,
                e.g. ``(1, 4, "<i4")`` for the second int of an inline struct; a table without
                the field reads 0.

        Raises:
            FlatBufferError: a table, vtable or field lies outside the buffer.
        """
        start, count = self.vector(slot, 4)
        data = np.frombuffer(self.buf, np.uint8)
        slots = start + 4 * np.arange(count, dtype=np.int64)
        tables = slots + _gather(data, slots, "<u4", "table offset")
        vtables = tables - _gather(data, tables, "<i4", "table")
        vtable_sizes = _gather(data, vtables, "<u2", "vtable")
        out = []
        for field, offset, dtype in columns:
            entry = 4 + 2 * field
            present = entry + 2 <= vtable_sizes
            field_offsets = np.zeros(count, np.int64)
            field_offsets[present] = _gather(data, vtables[present] + entry, "<u2", "vtable")
            present &= field_offsets != 0
            column = np.zeros(count, dtype)
            column[present] = _gather(
                data, tables[present] + field_offsets[present] + offset, dtype, f"field {field}"
            )
            out.append(column)
        return out

    def _target(self, slot: int) -> int | None:
        pos = self.field_pos(slot)
        if pos is None:
            return None
        return pos + _read(self.buf, _U32, pos, f"offset field {slot}")


def root_table(buf: bytes, identifier: bytes) -> FlatTable:
    """Return the root table of a size-prefixed buffer after checking prefix and identifier.

    Raises:
        FlatBufferError: the size prefix disagrees with the buffer length, or the file
            identifier is not ``identifier``.
    """
    size = _read(buf, _U32, 0, "size prefix")
    if size + 4 > len(buf) or size < 8:
        raise FlatBufferError(f"size prefix {size} does not fit a buffer of {len(buf)} bytes")
    found = bytes(buf[8:12])
    if found != identifier:
        raise FlatBufferError(f"file identifier is {found!r}, expected {identifier!r}")
    return FlatTable(buf, 4 + _read(buf, _U32, 4, "root offset"))


def _check(buf: bytes, pos: int, size: int, what: str) -> None:
    if pos < 0 or size < 0 or pos + size > len(buf):
        raise FlatBufferError(
            f"{what} at buffer position {pos} (+{size} bytes) lies outside the {len(buf)}-byte "
            "buffer; the packet is corrupt"
        )


def _gather(data: np.ndarray, positions: np.ndarray, dtype: str, what: str) -> np.ndarray:
    """The little-endian values of ``dtype`` at each of ``positions`` (bytes of ``data``)."""
    size = np.dtype(dtype).itemsize
    if len(positions) and (positions.min() < 0 or positions.max() + size > len(data)):
        bad = int(positions[(positions < 0) | (positions + size > len(data))][0])
        _check(data, bad, size, what)
    picked = data[positions[:, None] + np.arange(size)]
    return picked.view(dtype).reshape(len(positions)).astype(np.int64)


def _read(buf: bytes, codec: struct.Struct, pos: int, what: str) -> int:
    _check(buf, pos, codec.size, what)
    return codec.unpack_from(buf, pos)[0]


# ---- builder -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Scalar:
    """A scalar table field: ``fmt`` is a one-value ``struct`` format such as ``"<q"``."""

    slot: int
    fmt: str
    value: int | float


@dataclass(frozen=True)
class StructField:
    """An inline struct field with its ``struct`` format and alignment in bytes."""

    slot: int
    fmt: str
    values: tuple
    align: int = 4


@dataclass(frozen=True)
class VectorField:
    """A vector of ``count`` structs or scalars given as raw little-endian element bytes."""

    slot: int
    data: bytes
    count: int
    align: int = 4


@dataclass(frozen=True)
class StringField:
    """A UTF-8 string field."""

    slot: int
    text: str


@dataclass(frozen=True)
class TablesField:
    """A vector of tables, each given as a list of fields."""

    slot: int
    tables: list


def build_buffer(identifier: bytes, fields: list) -> bytes:
    """Build a size-prefixed FlatBuffer whose root table has ``fields``.

    Every given field is written, also when it equals the schema default, so a buffer's layout
    depends only on which fields are listed. Positions are aligned relative to the size prefix.
    """
    out = bytearray(12)
    out[8:12] = identifier
    root = _write_table(out, fields)
    _U32.pack_into(out, 4, root - 4)
    _pad(out, 8)
    _U32.pack_into(out, 0, len(out) - 4)
    return bytes(out)


def _pad(out: bytearray, align: int, phase: int = 0) -> None:
    out.extend(b"\0" * ((phase - len(out)) % align))


def _size_and_align(field) -> tuple[int, int]:
    if isinstance(field, Scalar):
        size = struct.calcsize(field.fmt)
        return size, size
    if isinstance(field, StructField):
        return struct.calcsize(field.fmt), field.align
    return 4, 4


def _inline_layout(fields: list) -> tuple[list, int, int]:
    """Place inline values after the 4-byte soffset, most aligned first.

    Returns:
        ``[(offset, field), ...]``, the table's inline size and its alignment in bytes.
    """
    ordered = sorted(fields, key=lambda field: -_size_and_align(field)[1])
    offset, placed, align = 4, [], 4
    for field in ordered:
        size, field_align = _size_and_align(field)
        offset += (-offset) % field_align
        placed.append((offset, field))
        offset += size
        align = max(align, field_align)
    return placed, offset, align


def _write_table(out: bytearray, fields: list) -> int:
    placed, table_size, align = _inline_layout(fields)
    slots = max([f.slot for f in fields], default=-1) + 1
    _pad(out, 2)
    vtable = len(out)
    entries = [0] * slots
    for offset, field in placed:
        entries[field.slot] = offset
    out.extend(struct.pack(f"<HH{slots}H", 4 + 2 * slots, table_size, *entries))
    _pad(out, align)
    table = len(out)
    out.extend(b"\0" * table_size)
    _I32.pack_into(out, table, table - vtable)
    for offset, field in placed:
        if isinstance(field, Scalar):
            struct.pack_into(field.fmt, out, table + offset, field.value)
        elif isinstance(field, StructField):
            struct.pack_into(field.fmt, out, table + offset, *field.values)
    for offset, field in placed:
        if not isinstance(field, (Scalar, StructField)):
            target = _write_child(out, field)
            _U32.pack_into(out, table + offset, target - (table + offset))
    return table


def _write_child(out: bytearray, field) -> int:
    """Append a string, vector or vector of tables; return the position of its length word."""
    if isinstance(field, TablesField):
        return _write_tables(out, field.tables)
    if isinstance(field, StringField):
        data, count, align = field.text.encode("utf-8") + b"\0", len(field.text.encode()), 4
    else:
        data, count, align = field.data, field.count, max(field.align, 4)
    _pad(out, align, phase=align - 4)
    start = len(out)
    out.extend(_U32.pack(count))
    out.extend(data)
    return start


def _write_tables(out: bytearray, tables: list) -> int:
    _pad(out, 4)
    start = len(out)
    out.extend(_U32.pack(len(tables)))
    out.extend(b"\0" * (4 * len(tables)))
    for index, fields in enumerate(tables):
        table = _write_table(out, fields)
        slot = start + 4 + 4 * index
        _U32.pack_into(out, slot, table - slot)
    return start
