"""The encoder: hand-computed words, and exact round trips through the decoder."""

import numpy as np
import pytest

from davis_io.errors import UsageError
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, TriggerKind
from davis_io.usb.encode import StreamEncoder, frame_words, time_words
from davis_io.usb.layout import SensorLayout
from davis_io.usb.words import WordDecoder

LAYOUT = SensorLayout()


def events(rows):
    return np.array(rows, dtype=EVENT_DTYPE)


def test_time_words_hand_computed():
    # 5 -> 98308: (98308 >> 15) - 0 = 3 wraps, then low bits 98308 & 0x7FFF = 4.
    assert time_words(5, 98308) == [0x7003, 0x8004]
    # 0 -> 2**31 + 1: 65536 wraps = 16 x 4095 + 16.
    assert time_words(0, 2**31 + 1) == [0x7FFF] * 16 + [0x7010, 0x8001]


def test_event_words_hand_computed():
    # Origin 1000: device times 5, 5, 7. Row words only when y changes.
    encoder = StreamEncoder(LAYOUT, time_origin_us=1000)
    words = encoder.encode_all(
        [Packet(events=events([(1005, 20, 10, 1), (1005, 21, 10, -1), (1007, 22, 11, 1)]))]
    )
    assert words.tolist() == [0x8005, 0x100A, 0x3014, 0x2015, 0x8007, 0x100B, 0x3016]


def test_frame_words_map_8_bit_values_to_10_bit_reads():
    # 8-bit value 200 -> 10-bit 800 -> reset 1023, signal 1023 - 800 = 223 (0x40DF).
    frame = Frame(np.array([[200]], np.uint8), 10, 20, 0, 30, bit_depth=8, position=(3, 4))
    words = frame_words(frame, LAYOUT, exposure_cycles=300)
    assert words["sof"].tolist() == [
        0x0008,
        0x5100,
        0x5203,
        0x5100,
        0x5204,
        0x5100,
        0x5203,
        0x5100,
        0x5204,
        0x6000 | 300,
        0x6000,
        0x6000,
        0x000B,
        0x43FF,
        0x000D,
    ]
    assert words["eoe"].tolist() == [0x000F, 0x000C, 0x40DF, 0x000D]


def test_frame_deeper_than_10_bits_or_for_davis240_is_refused():
    frame = Frame(np.zeros((2, 2), np.uint16), 0, 1, 0, 1, bit_depth=16)
    with pytest.raises(UsageError, match="depth 16"):
        frame_words(frame, LAYOUT, 0)
    with pytest.raises(UsageError, match="DAVIS240"):
        frame_words(frame, SensorLayout(adc_doubling=True), 0)


def random_packets(seed: int):
    rng = np.random.default_rng(seed)
    n = 50_000
    ev = np.zeros(n, EVENT_DTYPE)
    # A 100 ms gap in the middle forces wrap words with a multiplier of 3.
    t = np.sort(rng.integers(0, 200_000, n)) + 7_000_000
    t[n // 2 :] += 100_000
    ev["t"], ev["x"], ev["y"] = t, rng.integers(0, 346, n), rng.integers(0, 260, n)
    ev["p"] = rng.choice(np.array([-1, 1], np.int8), n)
    image = rng.integers(0, 1024, (260, 346)).astype(np.uint16)
    frame = Frame(image, 7_020_000, 7_023_000, 7_010_000, 7_033_000, bit_depth=10)
    imu = np.zeros(2, IMU_DTYPE)
    imu["t"] = [7_001_000, 7_002_000]
    imu["acc_g"] = [[0.5, -1.0, 0.25], [0.0, 0.125, -0.75]]  # multiples of 1/8192 g
    imu["gyro_dps"] = [[1 / 65.536, -2 / 65.536, 0.0], [0.0, 0.0, 10 / 65.536]]
    imu["temperature_c"] = [35 + 34 / 340, 35 - 17 / 340]
    triggers = np.array(
        [
            (7_005_000, TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE),
            (7_006_000, TriggerKind.APS_FRAME_START),
        ],
        dtype=TRIGGER_DTYPE,
    )
    return (
        ev,
        frame,
        imu,
        triggers,
        [
            Packet(events=ev[: n // 2], frames=[frame], imu=imu, triggers=triggers),
            Packet(events=ev[n // 2 :]),
        ],
    )


def test_round_trip_exact_for_events_frames_imu_and_external_triggers():
    ev, frame, imu, triggers, packets = random_packets(seed=3)
    origin = 6_900_000
    encoder = StreamEncoder(LAYOUT, time_origin_us=origin)
    data = encoder.encode_all(packets).astype("<u2").tobytes()
    decoder = WordDecoder(LAYOUT)
    out = [decoder.decode(data[i : i + 65537]) for i in range(0, len(data), 65537)]
    got = np.concatenate([p.events for p in out])
    got["t"] += origin
    assert np.array_equal(got, ev)
    (decoded,) = [f for p in out for f in p.frames]
    assert np.array_equal(decoded.image, frame.image)
    assert (
        decoded.readout_start_us + origin,
        decoded.exposure_start_us + origin,
        decoded.exposure_end_us + origin,
        decoded.readout_end_us + origin,
    ) == (7_010_000, 7_020_000, 7_023_000, 7_033_000)
    got_imu = np.concatenate([p.imu for p in out])
    np.testing.assert_array_equal(got_imu["acc_g"], imu["acc_g"])
    np.testing.assert_allclose(got_imu["gyro_dps"], imu["gyro_dps"], rtol=1e-6)
    np.testing.assert_allclose(got_imu["temperature_c"], imu["temperature_c"], rtol=1e-6)
    kinds = [k for p in out for k in p.triggers["kind"].tolist()]
    # The APS_FRAME_START trigger of the source is not encoded: frames carry their own markers.
    assert kinds.count(TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE) == 1
    assert kinds.count(TriggerKind.APS_FRAME_START) == 1
    assert encoder.stats.skipped_triggers == 1 and encoder.stats.late_records == 0
    assert decoder.stats.non_monotonic_times == 0


def test_empty_source_encodes_to_nothing():
    encoder = StreamEncoder(LAYOUT, time_origin_us=0)
    assert len(encoder.encode_all([Packet()])) == 0
