"""The minimal FlatBuffers reader and builder: layout by hand, round trips, bounds errors."""

import numpy as np
import pytest

from davis_io.aedat.aedat4_streams import RAW_EVENT_DTYPE
from davis_io.aedat.flatbuf import (
    FlatBufferError,
    Scalar,
    StringField,
    StructField,
    TablesField,
    VectorField,
    build_buffer,
    root_table,
)
from davis_io.types import EVENT_DTYPE

# A hand-made size-prefixed buffer, identifier "TEST", root table with slot 0 absent and slot 1
# an int32 0x01020304:
HAND_MADE = bytes.fromhex(
    "18000000"  # size prefix: 24 bytes follow
    "10000000"  # root uoffset at 4: table at 4 + 16 = 20
    "54455354"  # "TEST"
    "0800"
    "0800"
    "0000"
    "0400"  # vtable at 12: 8 bytes, table 8 bytes, slot 0 absent, slot 1 +4
    "08000000"  # table at 20: soffset 8 -> vtable at 20 - 8 = 12
    "04030201"  # slot 1 at 24: 0x01020304 little-endian
)


def test_reads_a_hand_made_buffer():
    table = root_table(HAND_MADE, b"TEST")
    assert table.pos == 20
    assert table.scalar(1, "<i") == 0x01020304
    assert table.scalar(0, "<q", -1) == -1  # absent: schema default
    assert table.scalar(7, "<h", 5) == 5  # beyond the vtable: schema default


def test_builder_round_trip_with_every_field_kind():
    data = build_buffer(
        b"ABCD",
        [
            Scalar(0, "<q", -(1 << 40)),
            Scalar(3, "<b", -3),
            StringField(1, "héllo"),
            VectorField(2, np.arange(3, dtype="<i8").tobytes(), 3, align=8),
            StructField(4, "<ii", (7, -8)),
            TablesField(5, [[Scalar(0, "<f", 1.5)], [Scalar(1, "<H", 9)]]),
        ],
    )
    assert len(data) % 8 == 0 and int.from_bytes(data[:4], "little") == len(data) - 4
    table = root_table(data, b"ABCD")
    assert table.scalar(0, "<q") == -(1 << 40) and table.scalar(3, "<b") == -3
    assert table.string(1) == "héllo"
    start, count = table.vector(2, 8)
    assert count == 3 and start % 8 == 0  # 8-byte elements aligned from the size prefix
    assert np.frombuffer(data, "<i8", count, start).tolist() == [0, 1, 2]
    assert table.struct_at(4, "<ii") == (7, -8)
    first, second = table.tables(5)
    assert first.scalar(0, "<f") == 1.5 and second.scalar(1, "<H") == 9
    assert second.scalar(0, "<f", 0.25) == 0.25


@pytest.mark.parametrize(
    "damage, match",
    [
        (lambda b: b[:6], "size prefix"),
        (lambda b: b[:8] + b"NOPE" + b[12:], "file identifier"),
        (lambda b: b[:4] + (10_000).to_bytes(4, "little") + b[8:], "outside"),
    ],
)
def test_damaged_buffers_raise_flatbuffer_error(damage, match):
    data = build_buffer(b"ABCD", [StringField(0, "x" * 40)])
    with pytest.raises(FlatBufferError, match=match):
        root_table(damage(data), b"ABCD").string(0)


def test_vector_longer_than_the_buffer_is_an_error():
    data = bytearray(build_buffer(b"ABCD", [VectorField(0, b"\1\2", 2, align=1)]))
    table = root_table(bytes(data), b"ABCD")
    start, _ = table.vector(0, 1)
    data[start - 4 : start] = (1 << 30).to_bytes(4, "little")
    with pytest.raises(FlatBufferError, match="vector 0"):
        root_table(bytes(data), b"ABCD").vector(0, 1)


def test_event_dtype_has_the_layout_of_the_file_event_struct():
    # decode_events views the file's 16-byte structs as EVENT_DTYPE in place
    assert EVENT_DTYPE.itemsize == RAW_EVENT_DTYPE.itemsize == 16
    for name in EVENT_DTYPE.names:
        assert EVENT_DTYPE.fields[name][1] == RAW_EVENT_DTYPE.fields[name][1]
        assert EVENT_DTYPE.fields[name][0].itemsize == RAW_EVENT_DTYPE.fields[name][0].itemsize
