"""Bad input: each malformed file gets a typed error or a warning naming where it went wrong."""

import numpy as np
import pytest

from davis_io.aedat import Aedat4Reader, Compression, RecordingWarning, open_recording
from davis_io.aedat.aedat4_header import (
    MAGIC,
    IOHeader,
    StreamDescription,
    build_info_node,
    build_io_header,
    compress,
)
from davis_io.aedat.aedat4_streams import encode_events
from davis_io.errors import FormatError
from davis_io.summary import summarize
from davis_io.types import EVENT_DTYPE


def _write(tmp_path, data, name="bad.aedat4"):
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _header(streams, compression=Compression.LZ4, table=-1):
    info = build_info_node(streams, compression)
    return MAGIC + build_io_header(IOHeader(compression, table, info))


def _packet(stream_id, payload):
    return np.array([stream_id, len(payload)], "<i4").tobytes() + payload


EVENTS = StreamDescription(0, "EVTS", "events", 346, 260, "DAVIS346_1")


@pytest.mark.parametrize(
    "start, match",
    [
        (b"", "empty file"),
        (b"hello world\r\n", "not an AEDAT header"),
        (b"#!AER-DAT3.0\r\n#!END-HEADER\r\n", "version '3.0' is not supported"),
    ],
)
def test_empty_wrong_magic_and_wrong_version(tmp_path, start, match):
    with pytest.raises(FormatError, match=match):
        open_recording(_write(tmp_path, start))


@pytest.mark.parametrize("data", [b"", b"#!AER-DAT2.0\r\n", b"#!AER-DAT4.1\r\n"])
def test_aedat4_reader_rejects_other_magic(tmp_path, data):
    with pytest.raises(FormatError, match="byte offset 0"):
        Aedat4Reader(_write(tmp_path, data))


def test_truncated_header_is_an_error(tmp_path, aestream_aedat4):
    with pytest.raises(FormatError, match="truncated header"):
        open_recording(_write(tmp_path, aestream_aedat4.read_bytes()[:100]))


@pytest.mark.parametrize(
    "data, fmt",
    [
        (b"#!AER-DAT3.1\r\n#Format: RAW\r\n#Source 1: DAVIS346\r\n#!END-HEADER\r\n", "AEDAT 3.1"),
        (b"#!AER-DAT2.0\r\n# AEChip: Davis346B\r\n#End Of ASCII Header\r\n", "AEDAT 2.0"),
    ],
)
def test_header_only_files_have_no_records(tmp_path, data, fmt):
    with open_recording(_write(tmp_path, data)) as source:
        summary = summarize(source)
    assert summary.format == fmt and summary.packets == 0 and summary.events.count == 0


def test_header_only_aedat4_has_no_records(tmp_path):
    with open_recording(_write(tmp_path, _header([EVENTS]))) as source:
        assert list(source) == []
        summary = summarize(source)
    assert summary.events.count == 0 and summary.time_range_us is None and summary.x_range is None


def test_truncated_file_returns_complete_packets_and_warns(tmp_path, aestream_aedat4):
    with Aedat4Reader(aestream_aedat4) as reader:
        cut_packet = reader.data_table[10]
    packet_offset = cut_packet.byte_offset - 8
    path = _write(tmp_path, aestream_aedat4.read_bytes()[: packet_offset + 100])
    with pytest.warns(RecordingWarning) as caught:
        with open_recording(path) as reader:
            packets = list(reader)
    messages = [str(w.message) for w in caught]
    assert any(f"truncated at byte offset {packet_offset}" in m for m in messages)
    assert any("data table position" in m for m in messages)
    assert len(packets) == 11  # packets 0..9 and a last, empty packet carrying the note
    assert packets[-1].is_empty and f"byte offset {packet_offset}" in packets[-1].notes[-1]
    assert packets[-1].truncated_at == packet_offset
    assert not any(p.is_empty for p in packets[:-1])
    assert all(p.truncated_at is None for p in packets[:-1])


@pytest.mark.parametrize("compression", [Compression.LZ4, Compression.ZSTD])
def test_corrupted_compressed_packet_names_packet_and_offset(tmp_path, compression):
    events = np.zeros(10, dtype=EVENT_DTYPE)
    events["p"] = 1
    good = compress(compression, encode_events(events))
    bad = b"\xde\xad\xbe\xef" + good[4:]  # the codec's frame magic destroyed
    head = _header([EVENTS], compression)
    second_offset = len(head) + 8 + len(good)
    path = _write(tmp_path, head + _packet(0, good) + _packet(0, bad))
    with open_recording(path) as reader:
        iterator = iter(reader)
        assert len(next(iterator).events) == 10
        with pytest.raises(FormatError, match=f"byte offset {second_offset}: packet 1 "):
            next(iterator)


def test_packets_before_a_corrupt_one_are_all_yielded(tmp_path):
    events = np.zeros(4, dtype=EVENT_DTYPE)
    payloads = []
    for index in range(9):
        events["t"] = index
        payloads.append(compress(Compression.LZ4, encode_events(events)))
    payloads[6] = b"\xde\xad\xbe\xef" + payloads[6][4:]
    path = _write(tmp_path, _header([EVENTS]) + b"".join(_packet(0, p) for p in payloads))
    seen = []
    with Aedat4Reader(path) as reader:
        with pytest.raises(FormatError, match="packet 6 "):
            for packet in reader:
                seen.append(int(packet.events["t"][0]))
    assert seen == [0, 1, 2, 3, 4, 5]


def test_unknown_stream_type_is_skipped_with_a_warning(tmp_path):
    boxes = StreamDescription(1, "EVTS", "boxes", 346, 260, "DAVIS346_1")
    streams = [EVENTS, boxes]
    events = np.zeros(3, dtype=EVENT_DTYPE)
    events["p"] = -1
    payload = compress(Compression.LZ4, encode_events(events))
    info = build_info_node(streams, Compression.LZ4).replace(
        '<attr key="typeIdentifier" type="string">EVTS</attr>\n            <node name="info" '
        'path="/mainloop/Recorder/outInfo/1/info/">',
        '<attr key="typeIdentifier" type="string">BBOX</attr>\n            <node name="info" '
        'path="/mainloop/Recorder/outInfo/1/info/">',
    )
    assert "BBOX" in info
    head = MAGIC + build_io_header(IOHeader(Compression.LZ4, -1, info))
    path = _write(tmp_path, head + _packet(1, b"xx") + _packet(7, b"yy") + _packet(0, payload))
    with pytest.warns(RecordingWarning) as caught:
        with open_recording(path) as reader:
            packets = list(reader)
    messages = " ".join(str(w.message) for w in caught)
    assert "stream 1 (type 'BBOX')" in messages and f"byte offset {len(head)}" in messages
    assert "stream 7 (not described in the infoNode)" in messages
    (packet,) = packets  # the notes travel with the next packet read
    assert len(packet.events) == 3 and len(packet.notes) == 2


def test_negative_packet_size_is_an_error(tmp_path):
    head = _header([EVENTS])
    path = _write(tmp_path, head + np.array([0, -5], "<i4").tobytes())
    with open_recording(path) as reader, pytest.raises(FormatError, match="negative size"):
        list(reader)
