"""The LZ4 frame decoders (liblz4 and python-lz4 block by block) against lz4.frame and hand-built
frames."""

import struct

import lz4.block
import lz4.frame
import numpy as np
import pytest

from davis_io.aedat import Aedat4Reader, Compression, write_aedat4
from davis_io.aedat.aedat4_header import (
    MAGIC,
    IOHeader,
    StreamDescription,
    build_info_node,
    build_io_header,
)
from davis_io.aedat.aedat4_streams import encode_events
from davis_io.aedat.liblz4 import system_liblz4
from davis_io.aedat.lz4_frame import FrameDecompressor, frame_layout, header_checksum
from davis_io.errors import FormatError
from davis_io.types import EVENT_DTYPE, Packet, SourceInfo

EVENTS = StreamDescription(0, "EVTS", "events", 346, 260, "DAVIS346_1")
FRAME_MAGIC = b"\x04\x22\x4d\x18"
RNG = np.random.default_rng(7)
RANDOM_64K = RNG.integers(0, 256, 65536, dtype=np.uint8).tobytes()
# 40 KiB of random bytes repeated: every match reaches 40 KiB back, across block boundaries.
REPEATED = (RNG.integers(0, 256, 40_000, dtype=np.uint8).tobytes() * 9)[:350_000]


@pytest.fixture(params=["liblz4", "python-lz4"])
def decode(request):
    """Decompress a frame to bytes with one decoder (liblz4 only where the system has it)."""
    native = request.param == "liblz4"
    if native and system_liblz4() is None:
        pytest.skip("this system has no liblz4")
    decompressor = FrameDecompressor(native=native)
    assert decompressor.native == native
    return lambda frame: decompressor.decompress(frame).tobytes()


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
def test_frames_from_lz4_frame_decode_block_by_block(options, decode):
    frame = lz4.frame.compress(REPEATED, **options)
    layout = frame_layout(frame)
    assert layout is not None and layout.linked == options["block_linked"]
    assert layout.content_size == (len(REPEATED) if options.get("store_size", True) else None)
    assert decode(frame) == REPEATED


def test_linked_blocks_need_the_previous_output():
    frame = lz4.frame.compress(REPEATED, block_linked=True)
    assert len(frame_layout(frame).blocks) == 6
    # Dropping the dictionary must break the later blocks: the test would notice a lost window.
    start, size, _ = frame_layout(frame).blocks[1]
    with pytest.raises(lz4.block.LZ4BlockError):
        lz4.block.decompress(frame[start : start + size], uncompressed_size=65536)


def test_uncompressed_block_serves_as_window_of_the_next(decode):
    second = RANDOM_64K[:30_000] + RANDOM_64K[40_000:50_000]
    frame = _frame([(RANDOM_64K, False), (_compressed(second, RANDOM_64K), True)])
    assert [b[2] for b in frame_layout(frame).blocks] == [False, True]
    assert decode(frame) == RANDOM_64K + second
    assert lz4.frame.decompress(frame) == RANDOM_64K + second  # the same reading as lz4.frame


def test_short_middle_block_keeps_the_older_window(decode):
    short = b"0123456789" * 100
    window = (RANDOM_64K + short)[-65536:]
    third = RANDOM_64K[2_000:9_000] + short[:500]  # reaches back past the short block
    blocks = [
        (RANDOM_64K, False),
        (_compressed(short, RANDOM_64K), True),
        (_compressed(third, window), True),
    ]
    assert decode(_frame(blocks)) == RANDOM_64K + short + third


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


def test_content_checksum_frame_decodes_and_a_bad_checksum_is_refused(decode):
    frame = lz4.frame.compress(REPEATED, content_checksum=True)
    assert decode(frame) == REPEATED
    with pytest.raises(RuntimeError):
        decode(frame[:-1] + bytes([frame[-1] ^ 0xFF]))


def test_corrupt_block_is_a_value_error(decode):
    frame = bytearray(lz4.frame.compress(REPEATED, block_linked=True))
    start, size, _ = frame_layout(bytes(frame)).blocks[2]
    frame[start : start + size] = b"\xff" * size
    assert frame_layout(bytes(frame)) is not None  # the fast path meets the damage
    with pytest.raises(ValueError, match="corrupt"):
        decode(bytes(frame))


def test_content_size_mismatch_is_a_value_error(decode):
    frame = bytearray(lz4.frame.compress(b"x" * 1000, store_size=True))
    frame[6:14] = struct.pack("<Q", 999)
    frame[14] = header_checksum(bytes(frame[4:14]))
    with pytest.raises(ValueError, match="header says 999|frameSize_wrong"):
        decode(bytes(frame))


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


def test_one_decompressor_across_frame_sizes(decode):
    sizes = [350_000, 1_000, 200_000, 0, 350_000, 70_000]
    for size in sizes:
        data = REPEATED[size // 3 : size // 3 + size]
        frame = lz4.frame.compress(data, store_size=False, block_linked=True)
        assert frame_layout(frame) is not None
        assert decode(frame) == data  # nothing left from a longer frame


def test_each_result_is_a_new_writable_array():
    decompressor = FrameDecompressor()
    first = decompressor.decompress(lz4.frame.compress(b"a" * 5000))
    second = decompressor.decompress(lz4.frame.compress(b"b" * 5000))
    assert first.tobytes() == b"a" * 5000 and second.tobytes() == b"b" * 5000
    first[:] = 0  # the caller owns it: events are decoded in place
    assert second.tobytes() == b"b" * 5000


def test_both_decoders_agree_on_every_packet_of_the_real_recording(aestream_aedat4):
    if system_liblz4() is None:
        pytest.skip("this system has no liblz4")
    with Aedat4Reader(aestream_aedat4) as reader:
        payloads = [
            reader._read_at(reader._payload_offset(i, row), row.size)
            for i, row in enumerate(reader.data_table)
        ]
    native, fallback = FrameDecompressor(native=True), FrameDecompressor(native=False)
    for payload in payloads:
        assert frame_layout(payload) is not None  # DV's frames take the fast paths
        assert native.decompress(payload).tobytes() == fallback.decompress(payload).tobytes()
        assert native.decompress(payload).tobytes() == lz4.frame.decompress(payload)


def test_native_decoder_refuses_a_frame_larger_than_the_array():
    if system_liblz4() is None:
        pytest.skip("this system has no liblz4")
    from davis_io.aedat.liblz4 import NativeFrameDecoder

    decoder = NativeFrameDecoder(system_liblz4())
    frame = lz4.frame.compress(REPEATED, store_size=False)
    with pytest.raises(ValueError, match="LZ4 frame is"):
        decoder.decode_into(frame, np.empty(1000, np.uint8))
    out = np.empty(len(REPEATED), np.uint8)  # the context recovers for the next frame
    assert decoder.decode_into(frame, out) == len(REPEATED) and out.tobytes() == REPEATED


@pytest.mark.parametrize("compression", [Compression.LZ4, Compression.NONE])
def test_packets_read_earlier_keep_their_events(tmp_path, compression):
    # Shrinking and growing packets: a packet that still pointed into the reused
    # decompression buffer would show a later packet's events.
    sizes = [9000, 200, 30_000, 5000, 30_000, 1]
    packets = []
    for i, size in enumerate(sizes):
        events = np.zeros(size, dtype=EVENT_DTYPE)
        events["t"] = 1_000_000 * i + np.arange(size)
        events["x"] = i
        events["p"] = np.where(np.arange(size) % 3 == 0, 1, -1)
        packets.append(Packet(events=events))
    info = SourceInfo(camera="DAVIS346", serial="1", width=346, height=260)
    path = write_aedat4(packets, tmp_path / "sizes.aedat4", info, compression=compression)
    with Aedat4Reader(path) as reader:
        read = [p for p in reader if len(p.events)]
    assert [len(p.events) for p in read] == sizes
    for ours, written in zip(read, packets, strict=True):
        assert np.array_equal(ours.events, written.events)


def test_the_reader_gives_the_same_events_with_python_lz4_only(aestream_aedat4):
    def events(native):
        with Aedat4Reader(aestream_aedat4, native_lz4=native) as reader:
            return np.concatenate([p.events for p in reader if len(p.events)])

    fallback = events(False)
    assert len(fallback) == 117_667
    assert np.array_equal(fallback, events(None))
