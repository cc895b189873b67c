"""Raw bulk-IN dumps: written by the encoder, decoded by ``open_raw_usb_dump``."""

import numpy as np
import pytest

from davis_io.errors import FormatError, UsageError
from davis_io.types import EVENT_DTYPE, Packet
from davis_io.usb.dump import open_raw_usb_dump, write_raw_usb_dump


def events(n: int) -> np.ndarray:
    rng = np.random.default_rng(11)
    ev = np.zeros(n, EVENT_DTYPE)
    ev["t"] = np.sort(rng.integers(50_000, 3_000_000, n))
    ev["x"], ev["y"] = rng.integers(0, 346, n), rng.integers(0, 260, n)
    ev["p"] = rng.choice(np.array([-1, 1], np.int8), n)
    return ev


def read_all(path, model="davis346"):
    with open_raw_usb_dump(path, model) as dump:
        packets = list(dump)
    return dump, packets


def test_dump_round_trip(tmp_path, list_source):
    ev = events(400_000)
    path = tmp_path / "stream.bin"
    written = write_raw_usb_dump(
        list_source([Packet(events=ev[:200_000]), Packet(events=ev[200_000:])]), path
    )
    assert written == path.stat().st_size and written % 2 == 0
    # The first two bytes are the timestamp reset word 0x0001, little-endian.
    assert path.read_bytes()[:2] == b"\x01\x00"
    dump, packets = read_all(path)
    got = np.concatenate([p.events for p in packets])
    # Device time 0 is 200 ms before the first record.
    got["t"] += int(ev["t"][0]) - 200_000
    assert np.array_equal(got, ev)
    assert dump.info.camera == "DAVIS346" and dump.info.width == 346


def test_truncated_dump_yields_every_complete_word(tmp_path):
    path = tmp_path / "cut.bin"
    # reset, t=5, row 1, column 2 ON, then half of a column word.
    path.write_bytes(np.array([0x0001, 0x8005, 0x1001, 0x3002], "<u2").tobytes() + b"\x03")
    dump, packets = read_all(path)
    assert np.concatenate([p.events for p in packets]).tolist() == [(5, 2, 1, 1)]
    assert dump.decoder.stats.trailing_bytes == 1
    assert any("half a word" in note for p in packets for note in p.notes)


def test_empty_dump(tmp_path):
    path = tmp_path / "empty.bin"
    path.write_bytes(b"")
    _, packets = read_all(path)
    assert sum(len(p.events) for p in packets) == 0


def test_bad_model_and_missing_file(tmp_path):
    with pytest.raises(UsageError, match="unknown camera model 'davis999'"):
        open_raw_usb_dump(tmp_path / "x.bin", "davis999")
    with (
        pytest.raises(FormatError, match="cannot open raw USB dump"),
        open_raw_usb_dump(tmp_path / "missing.bin", "davis346"),
    ):
        pass


def test_davis240_dump_uses_its_array_size(tmp_path):
    path = tmp_path / "240.bin"
    # Column 300 is beyond a DAVIS240's 240 columns: skipped and counted.
    path.write_bytes(np.array([0x0001, 0x8001, 0x1000, 0x312C, 0x30EF], "<u2").tobytes())
    dump, packets = read_all(path, "DAVIS240")
    assert np.concatenate([p.events for p in packets])["x"].tolist() == [239]
    assert dump.decoder.stats.out_of_range_addresses == 1
