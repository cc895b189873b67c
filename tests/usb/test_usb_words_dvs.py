"""Hand-computed word sequences (davis-protocol.md §3.2-3.5): timestamps, wraps, resets, DVS."""

import numpy as np

from davis_io.types import TriggerKind
from davis_io.usb.layout import SensorLayout
from davis_io.usb.words import WordDecoder


def le_bytes(*words: int) -> bytes:
    return np.array(words, dtype="<u2").tobytes()


def decode(*words: int, layout: SensorLayout | None = None):
    decoder = WordDecoder(layout or SensorLayout())
    return decoder.decode(le_bytes(*words)), decoder


def test_empty_input_gives_empty_packet():
    packet, decoder = decode()
    assert len(packet.events) == 0 and len(packet.triggers) == 0 and packet.frames == []
    assert packet.events.dtype.names == ("t", "x", "y", "p")
    assert decoder.stats.words == 0


def test_row_column_polarity_and_timestamp():
    # 0x8005: bit 15 set -> timestamp word, low 15 bits = 5 µs.
    # 0x100A: code 1 (row) data 10; 0x3014: code 3 (column, ON) x=20; 0x2015: code 2 (OFF) x=21.
    # 0x8007: time 7; 0x3016: same row 10 is sticky, x=22 ON.
    packet, decoder = decode(0x8005, 0x100A, 0x3014, 0x2015, 0x8007, 0x3016)
    assert packet.events.tolist() == [(5, 20, 10, 1), (5, 21, 10, -1), (7, 22, 10, 1)]
    assert decoder.stats.events == 3


def test_wrap_word_multiplies_by_its_data():
    # 0x8100: t = 0x100 = 256; 0x7003: wrap x3 -> wrapAdd = 3 * 32768 = 98304, current = 98304;
    # 0x1001 row 1; 0x3002 column 2 ON at 98304; 0x8004: t = 98304 + 4 = 98308; 0x2003 OFF x=3.
    packet, decoder = decode(0x8100, 0x7003, 0x1001, 0x3002, 0x8004, 0x2003)
    assert packet.events.tolist() == [(98304, 2, 1, 1), (98308, 3, 1, -1)]
    assert decoder.time_us == 98308
    assert decoder.stats.non_monotonic_times == 0


def test_big_wrap_past_31_bits_keeps_counting():
    # 16 wraps of 4095 and one of 16: (16 * 4095 + 16) * 32768 = 65536 * 32768 = 2**31 µs.
    # 0x8001 then gives 2**31 + 1, which a 31-bit counter could not hold.
    words = [0x7FFF] * 16 + [0x7010, 0x8001, 0x1000, 0x3000]
    packet, _ = decode(*words)
    assert packet.events["t"].tolist() == [2**31 + 1]


def test_first_timestamp_reset_is_time_zero_whatever_came_before():
    # Start-up left-overs: a wrap word (0x7001: +32768 µs) and a timestamp 0x8100 (256 µs past
    # it); then the reset (0x0001) and device time 0x8005: 5 µs after the reset, not 32768 + 5.
    packet, decoder = decode(0x7001, 0x8100, 0x0001, 0x8005, 0x1002, 0x3004)
    assert packet.events.tolist() == [(5, 4, 2, 1)]
    assert packet.triggers.tolist() == [(0, TriggerKind.TIMESTAMP_RESET)]
    assert decoder.stats.timestamp_resets == 1


def test_a_later_reset_zeroes_the_device_time_and_continues_the_output_time_line():
    # Reset at start, t = 0x7000 = 28672, a wrap word (+32768 µs: 32768), reset mid-stream,
    # then device 5 µs: output 32768 + 5 = 32773 (the line never goes backwards; the wrap sum
    # and current time are zeroed, so the second wrap word counts from the reset).
    words = (0x0001, 0x8000 | 0x7000, 0x1002, 0x3001, 0x7001, 0x0001, 0x8005, 0x3004, 0x7001)
    packet, decoder = decode(*words, 0x8003, 0x3005)
    assert packet.events.tolist() == [(28672, 1, 2, 1), (32773, 4, 2, 1), (65539, 5, 2, 1)]
    assert packet.triggers["t"].tolist() == [0, 32768]
    assert decoder.stats.timestamp_resets == 2


def test_non_monotonic_time_is_counted_not_corrected():
    # 0x8010 (16) then 0x8008 (8): time goes back by 8 µs; the event keeps t = 8.
    packet, decoder = decode(0x8010, 0x8008, 0x1000, 0x2000)
    assert packet.events["t"].tolist() == [8]
    assert decoder.stats.non_monotonic_times == 1


def test_out_of_range_addresses_and_missing_row_are_skipped_and_counted():
    # 0x3001 before any row: no event (columns_without_row). Row 260 (0x1104) is out of range
    # for 260 rows: ignored, so row stays 5; column 346 (0x315A) out of range: skipped.
    packet, decoder = decode(0x3001, 0x1005, 0x1104, 0x315A, 0x3159)
    assert packet.events[["x", "y"]].tolist() == [(345, 5)]
    assert decoder.stats.columns_without_row == 1
    assert decoder.stats.out_of_range_addresses == 2


def test_invert_xy_swaps_row_and_column():
    # invertXY: x = row data (7), y = column data (9).
    layout = SensorLayout(dvs_invert_xy=True)
    packet, _ = decode(0x1007, 0x3009, layout=layout)
    assert packet.events[["x", "y"]].tolist() == [(7, 9)]


def test_state_carries_across_calls_and_split_words():
    decoder = WordDecoder(SensorLayout())
    data = le_bytes(0x8003, 0x1004, 0x3005, 0x2006)
    # Split inside the second word and inside the fourth: 3 + 4 + 1 bytes.
    first = decoder.decode(data[:3])
    second = decoder.decode(data[3:7])
    third = decoder.decode(data[7:])
    events = np.concatenate([first.events, second.events, third.events])
    assert events.tolist() == [(3, 5, 4, 1), (3, 6, 4, -1)]
    assert decoder.stats.split_words == 2
    assert decoder.finish().notes == []


def test_trailing_odd_byte_is_counted_at_the_end():
    decoder = WordDecoder(SensorLayout())
    packet = decoder.decode(le_bytes(0x8001, 0x1000, 0x3000) + b"\x05")
    assert len(packet.events) == 1
    tail = decoder.finish()
    assert decoder.stats.trailing_bytes == 1 and len(tail.notes) == 1


def test_external_input_and_generator_specials_become_triggers():
    # Device codes 2 falling, 3 rising, 4 pulse, 16 generator falling, 17 generator rising.
    packet, _ = decode(0x8009, 0x0002, 0x0003, 0x0004, 0x0010, 0x0011)
    assert packet.triggers["t"].tolist() == [9] * 5
    assert packet.triggers["kind"].tolist() == [
        TriggerKind.EXTERNAL_SIGNAL_FALLING_EDGE,
        TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE,
        TriggerKind.EXTERNAL_SIGNAL_PULSE,
        TriggerKind.EXTERNAL_GENERATOR_FALLING_EDGE,
        TriggerKind.EXTERNAL_GENERATOR_RISING_EDGE,
    ]


def test_unknown_codes_are_counted_never_fatal():
    # Special 0 (reserved), 6 (unused), 18 (undefined); misc-8 sub-code 7; misc-10 sub-code 1.
    packet, decoder = decode(0x0000, 0x0006, 0x0012, 0x5700, 0x6400, 0x1001, 0x3001)
    assert decoder.stats.unknown_words == 5
    assert len(packet.events) == 1
