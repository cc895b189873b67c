"""The block-by-block LZ4 frame decoder against lz4.frame and hand-built frames."""

import struct

import lz4.block
import lz4.frame
import numpy as np
import pytest

from davis_io.aedat import Aedat4Reader, Compression
from davis_io.aedat.aedat4_header import (
    MAGIC,
    IOHeader,
    StreamDescription,
    build_info_node,
    build_io_header,
)
from davis_io.aedat.aedat4_streams import encode_events
from davis_io.aedat.lz4_frame import decompress_frame, frame_layout, header_checksum
from davis_io.errors import FormatError
from davis_io.types import EVENT_DTYPE

EVENTS = StreamDescription(0, "EVTS", "events", 346, 260, "DAVIS346_1")
FRAME_MAGIC = b"\x04\x22\x4d\x18"
RNG = np.random.default_rng(7)
RANDOM_64K = RNG.integers(0, 256, 65536, dtype=np.uint8).tobytes()
# 40 KiB of random bytes repeated: every match reaches 40 KiB back, across block boundaries.
REPEATED = (RNG.integers(0, 256, 40_000, dtype=np.uint8).tobytes() * 9)[:350_000]


def _frame(blocks, flg=0x40, bd=0x40, trailer=b""):
    """A frame from ``[(bytes, compressed), ...]`` with its header checksum computed here."""
    descriptor = bytes([flg, bd])
    out = FRAME_MAGIC + descriptor + bytes([header_checksum(descriptor)])
    for data, compressed in blocks:
        out += struct.pack("<I", len(data) | (0 if compressed else 0x8000_0000)) + data
    return out + b"\0\0\0\0" + trailer


def _compressed(data, window=b""):
    return lz4.block.compress(data, store_size=False, dict=window)


def test_header_checksum_of_dv_descriptor():
    # DV's packets start 04 22 4D 18 40 40 C0: linked 64 KiB blocks, HC 0xC0.
    assert header_checksum(b"\x40\x40") == 0xC0
    with_size = lz4.frame.compress(b"abc", store_size=True)
    assert header_checksum(with_size[4:14]) == with_size[14]


@pytest.mark.parametrize(
    "options",
    [
        {"block_linked": True, "store_size": False},
        {"block_linked": True, "store_size": True},
        {"block_linked": False, "store_size": False},
        {"block_linked": True, "block_size": lz4.frame.BLOCKSIZE_MAX256KB},
        {"block_linked": False, "block_size": lz4.frame.BLOCKSIZE_MAX1MB, "store_size": True},
    ],
)
def test_frames_from_lz4_frame_decode_block_by_block(options):
    frame = lz4.frame.compress(REPEATED, **options)
    layout = frame_layout(frame)
    assert layout is not None and layout.linked == options["block_linked"]
    assert layout.content_size == (len(REPEATED) if options.get("store_size", True) else None)
    assert decompress_frame(frame) == REPEATED


def test_linked_blocks_need_the_previous_output():
    frame = lz4.frame.compress(REPEATED, block_linked=True)
    assert len(frame_layout(frame).blocks) == 6
    # Dropping the dictionary must break the later blocks: the test would notice a lost window.
    start, size, _ = frame_layout(frame).blocks[1]
    with pytest.raises(lz4.block.LZ4BlockError):
        lz4.block.decompress(frame[start : start + size], uncompressed_size=65536)


def test_uncompressed_block_serves_as_window_of_the_next():
    second = RANDOM_64K[:30_000] + RANDOM_64K[40_000:50_000]
    frame = _frame([(RANDOM_64K, False), (_compressed(second, RANDOM_64K), True)])
    assert [b[2] for b in frame_layout(frame).blocks] == [False, True]
    assert decompress_frame(frame) == RANDOM_64K + second
    assert lz4.frame.decompress(frame) == RANDOM_64K + second  # the same reading as lz4.frame


def test_short_middle_block_keeps_the_older_window():
    short = b"0123456789" * 100
    window = (RANDOM_64K + short)[-65536:]
    third = RANDOM_64K[2_000:9_000] + short[:500]  # reaches back past the short block
    blocks = [
        (RANDOM_64K, False),
        (_compressed(short, RANDOM_64K), True),
        (_compressed(third, window), True),
    ]
    assert decompress_frame(_frame(blocks)) == RANDOM_64K + short + third


@pytest.mark.parametrize(
    "frame",
    [
        lz4.frame.compress(REPEATED, content_checksum=True),
        lz4.frame.compress(REPEATED, block_checksum=True),
        _frame([(b"tail", False)], trailer=b"extra"),
        _frame([(b"tail", False)])[:-2],  # no end mark
        _frame([(b"tail", False)], flg=0x41),  # dictionary id flag without an id
        FRAME_MAGIC + b"\x40\x40\x00" + b"\0" * 4,  # header checksum wrong
    ],
    ids=["content-checksum", "block-checksum", "trailing", "no-end", "dict-id", "bad-hc"],
)
def test_unusual_frames_go_to_lz4_frame(frame):
    assert frame_layout(frame) is None


def test_content_checksum_frame_decodes_and_a_bad_checksum_is_refused():
    frame = lz4.frame.compress(REPEATED, content_checksum=True)
    assert decompress_frame(frame) == REPEATED
    with pytest.raises(RuntimeError):
        decompress_frame(frame[:-1] + bytes([frame[-1] ^ 0xFF]))


def test_corrupt_block_is_a_value_error():
    frame = bytearray(lz4.frame.compress(REPEATED, block_linked=True))
    start, size, _ = frame_layout(bytes(frame)).blocks[2]
    frame[start : start + size] = b"\xff" * size
    assert frame_layout(bytes(frame)) is not None  # the fast path meets the damage
    with pytest.raises(ValueError, match="LZ4 block at frame byte"):
        decompress_frame(bytes(frame))


def test_content_size_mismatch_is_a_value_error():
    frame = bytearray(lz4.frame.compress(b"x" * 1000, store_size=True))
    frame[6:14] = struct.pack("<Q", 999)
    frame[14] = header_checksum(bytes(frame[4:14]))
    with pytest.raises(ValueError, match="header says 999"):
        decompress_frame(bytes(frame))


@pytest.mark.parametrize("damage", ["block", "header-checksum"])
def test_reader_names_the_packet_offset_of_a_bad_frame(tmp_path, damage):
    events = np.zeros(20_000, dtype=EVENT_DTYPE)
    events["t"] = np.arange(20_000)
    events["p"] = 1
    good = lz4.frame.compress(encode_events(events), store_size=False, block_linked=True)
    bad = bytearray(good)
    if damage == "block":
        start, size, _ = frame_layout(good).blocks[1]
        bad[start : start + size] = b"\xff" * size
    else:
        bad[6] ^= 0xFF  # lz4.frame refuses the header checksum
    head = MAGIC + build_io_header(
        IOHeader(Compression.LZ4, -1, build_info_node([EVENTS], Compression.LZ4))
    )
    packets = [good, good, bytes(bad)]
    bad_offset = len(head) + 2 * (8 + len(good))
    data = head + b"".join(struct.pack("<ii", 0, len(p)) + p for p in packets)
    path = tmp_path / "bad.aedat4"
    path.write_bytes(data)
    with Aedat4Reader(path) as reader:
        iterator = iter(reader)
        assert np.array_equal(next(iterator).events, events)
        assert np.array_equal(next(iterator).events, events)
        with pytest.raises(FormatError, match=f"byte offset {bad_offset}: packet 2 ") as caught:
            next(iterator)
    assert caught.value.offset == bad_offset
