"""EVTS decoding against hand-built 16-byte event structs."""

import struct

from davis_io.aedat.aedat4_streams import decode_events
from davis_io.aedat.flatbuf import VectorField, build_buffer

# (timestamp, x, y, polarity byte, padding bytes) as DV's 16-byte little-endian struct
RAW = [
    (1633953690975950, 0, 259, 1, b"\0\0\0"),
    (-5, 345, 0, 0, b"\xff\xff\xff"),  # padding must be ignored
    (1 << 40, 7, 128, 2, b"\x01\x02\x03"),  # any non-zero polarity byte is ON
    (9, 65535, 1, 255, b"\0\0\0"),
    (10, 12, 13, 0, b"\0\0\0"),
]


def _packet(rows):
    data = b"".join(struct.pack("<qHHB", t, x, y, p) + pad for t, x, y, p, pad in rows)
    return build_buffer(b"EVTS", [VectorField(0, data, len(rows), align=8)])


def test_fields_and_polarity_from_hand_built_structs():
    events = decode_events(_packet(RAW))
    assert events["t"].tolist() == [1633953690975950, -5, 1 << 40, 9, 10]
    assert events["x"].tolist() == [0, 345, 7, 65535, 12]
    assert events["y"].tolist() == [259, 0, 128, 1, 13]
    assert events["p"].tolist() == [1, -1, 1, 1, -1]


def test_result_owns_its_memory():
    buf = bytearray(_packet(RAW))
    events = decode_events(bytes(buf))
    assert events.flags.owndata and events.flags.writeable
    events["t"][0] = 0  # writable, and no view into the packet buffer
    assert decode_events(bytes(buf))["t"][0] == 1633953690975950


def test_empty_packet():
    events = decode_events(_packet([]))
    assert len(events) == 0 and events.dtype.names == ("t", "x", "y", "p")
