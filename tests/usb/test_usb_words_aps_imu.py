"""Hand-computed APS frame and IMU word sequences (davis-protocol.md §3.3, 3.6-3.8)."""

import numpy as np
import pytest

from davis_io.types import TriggerKind
from davis_io.usb.layout import SensorLayout
from davis_io.usb.words import WordDecoder


def le_bytes(words) -> bytes:
    return np.array(words, dtype="<u2").tobytes()


# A 2 x 3 frame at ROI (4, 5)-(5, 7) of a DAVIS346, global shutter.
ROI_WORDS = [0x5100, 0x5204, 0x5100, 0x5205, 0x5100, 0x5205, 0x5100, 0x5207]
# Exposure 90000 ADC cycles (3000 µs at 30 MHz) = 0x15F90: 10-bit chunks, least significant
# first: 90000 & 0x3FF = 0x390, (90000 >> 10) & 0x3FF = 0x57, then 0.
EXPOSURE_WORDS = [0x6390, 0x6057, 0x6000]
# Reset reads (0x000B opens a reset column, 0x4xxx samples, 0x000D ends it):
# column 0: 600, 600, 300; column 1: 600, 600, 600.
RESET_COLUMNS = [0x000B, 0x4258, 0x4258, 0x412C, 0x000D, 0x000B, 0x4258, 0x4258, 0x4258, 0x000D]
# Signal reads (0x000C opens a signal column):
# column 0: 400, 768, 100; column 1: 0, 600, 1.
SIGNAL_COLUMNS = [0x000C, 0x4190, 0x4300, 0x4064, 0x000D, 0x000C, 0x4000, 0x4258, 0x4001, 0x000D]
FRAME = [
    0x8010,
    0x0008,
    *ROI_WORDS,
    *EXPOSURE_WORDS,
    *RESET_COLUMNS,
    0x8020,
    0x000E,
    0x8030,
    0x000F,
    *SIGNAL_COLUMNS,
    0x8040,
    0x000A,
]
# CDS per pixel (column c, sample n): 600-400 = 200; 600-768 < 0 -> 0; reset 300 < 384 -> 1023;
# signal 0 -> 1023; 600-600 = 0; 600-1 = 599. Image row y = sample n, column x = column c.
EXPECTED_IMAGE = [[200, 1023], [0, 0], [1023, 599]]


def decode(words, layout=None):
    decoder = WordDecoder(layout or SensorLayout())
    return decoder.decode(le_bytes(words)), decoder


def test_frame_pixels_times_roi_exposure_and_markers():
    packet, decoder = decode(FRAME)
    (frame,) = packet.frames
    assert frame.image.dtype == np.uint16 and frame.bit_depth == 10
    assert frame.image.tolist() == EXPECTED_IMAGE
    assert (frame.readout_start_us, frame.exposure_start_us) == (16, 32)
    assert (frame.exposure_end_us, frame.readout_end_us) == (48, 64)
    assert frame.position == (4, 5)
    assert decoder.frame_exposure_cycles == 90000
    assert packet.triggers.tolist() == [
        (16, TriggerKind.APS_FRAME_START),
        (32, TriggerKind.APS_EXPOSURE_START),
        (48, TriggerKind.APS_EXPOSURE_END),
        (64, TriggerKind.APS_FRAME_END),
    ]


@pytest.mark.parametrize(
    ("orientation", "expected"),
    [
        (0b010, [[1023, 200], [0, 0], [599, 1023]]),  # flipX: column c -> C-1-c
        (0b001, [[1023, 599], [0, 0], [200, 1023]]),  # flipY: sample n -> R-1-n
    ],
)
def test_frame_flips(orientation, expected):
    packet, _ = decode(FRAME, SensorLayout(aps_orientation=orientation))
    assert packet.frames[0].image.tolist() == expected


def test_davis240_doubles_samples_before_cds():
    # Doubled resets 1200, 1200, 600 / 1200 x3; signals 800, 1536, 200 / 0, 1200, 2:
    # 400; 1200-1536 < 0 -> 0; 600 >= 384 and 200 != 0 -> 400; signal 0 -> 1023; 0;
    # 1198 clamped to 1023.
    packet, _ = decode(FRAME, SensorLayout(adc_doubling=True))
    assert packet.frames[0].image.tolist() == [[400, 1023], [0, 0], [400, 1023]]


def test_frame_with_a_missing_column_end_is_dropped_but_markers_remain():
    words = list(FRAME)
    del words[words.index(0x000A) - 2]  # the last 0x000D: signal read has only 1 column
    packet, decoder = decode(words)
    assert packet.frames == []
    assert decoder.stats.frames_dropped == 1
    assert packet.triggers["kind"].tolist()[-1] == TriggerKind.APS_FRAME_END


def test_aps_data_before_the_first_frame_start_is_ignored():
    # Start-up: column markers, samples, exposure markers and frame end before any 0x0008.
    packet, decoder = decode([0x8001, 0x000B, 0x4100, 0x000D, 0x000E, 0x000F, 0x000A, *FRAME])
    assert len(packet.frames) == 1
    assert packet.triggers["t"].tolist() == [16, 32, 48, 64]


def test_timestamp_reset_cuts_a_frame_in_progress():
    cut = FRAME.index(0x000E)
    packet, decoder = decode(FRAME[:cut] + [0x0001] + FRAME[cut:])
    assert packet.frames == []
    assert decoder.stats.frames_dropped == 1


# IMU sample: start (0x0005), config 0x53E5 = sub-code 3, byte 0b111_001_01: all three sensors
# on, accel index 1 (8192 LSB/g), gyro index 1 (65.536 LSB/(deg/s)); 14 bytes big-endian;
# end (0x0007) at t = 512.
IMU_BYTES = [
    0x20,
    0x00,  # accel x 0x2000 = 8192 -> 1 g
    0xF0,
    0x00,  # accel y 0xF000 = -4096 -> -0.5 g
    0x00,
    0x00,  # accel z 0
    0x01,
    0x54,  # temperature 0x0154 = 340 -> 340/340 + 35 = 36 C
    0x02,
    0x8F,  # gyro x 655 -> 655/65.536 = 9.99451 deg/s
    0xFF,
    0x7D,  # gyro y -131 -> -1.99890 deg/s
    0x00,
    0x41,
]  # gyro z 65 -> 0.99182 deg/s
IMU = [0x8100, 0x0005, 0x53E5, *[0x5000 | b for b in IMU_BYTES], 0x8200, 0x0007]


def test_imu_sample_with_scales():
    packet, decoder = decode(IMU)
    (sample,) = packet.imu
    assert sample["t"] == 512
    np.testing.assert_allclose(sample["acc_g"], [1.0, -0.5, 0.0])
    np.testing.assert_allclose(sample["gyro_dps"], [9.99451, -1.99890, 0.99182], atol=1e-5)
    assert sample["temperature_c"] == pytest.approx(36.0)
    assert decoder.stats.imu_samples == 1


def test_imu_flip_x_and_mpu9250_temperature():
    # flipX negates accel x and gyro x; MPU-9250: 340 / 333.87 + 21 = 22.01836 C.
    packet, _ = decode(IMU, SensorLayout(imu_orientation=0b100, imu_type=2))
    assert packet.imu["acc_g"][0][0] == -1.0
    assert packet.imu["gyro_dps"][0][0] == pytest.approx(-9.99451, abs=1e-5)
    assert packet.imu["temperature_c"][0] == pytest.approx(22.01836, abs=1e-5)


def test_imu_accelerometer_only_skips_temperature_and_gyro():
    # Config 0x5380: only accel (bit 7), index 0 -> 16384 LSB/g; 6 bytes then the counter jumps
    # from 6 past temperature (8) and gyro (14): complete.
    words = [0x8001, 0x0005, 0x5380, 0x5040, 0x5000, 0x5000, 0x5000, 0x50C0, 0x5000, 0x0007]
    packet, _ = decode(words)
    np.testing.assert_allclose(packet.imu["acc_g"][0], [1.0, 0.0, -1.0])  # 0xC000 = -16384
    np.testing.assert_allclose(packet.imu["gyro_dps"][0], [0.0, 0.0, 0.0])


def test_incomplete_imu_sample_is_dropped_and_imu_before_start_ignored():
    # IMU bytes and an end marker before any IMU start are ignored (no count);
    # then a sample with only 4 of 14 bytes is dropped at its end marker.
    words = [0x5001, 0x0007, 0x0005, 0x53E5, 0x5001, 0x5002, 0x5003, 0x5004, 0x0007]
    packet, decoder = decode(words)
    assert len(packet.imu) == 0
    assert decoder.stats.imu_dropped == 1


def test_rolling_shutter_frame_start_is_handled_the_same():
    # Special 9 (rolling shutter) instead of 8: same frame, same APS_FRAME_START trigger.
    words = [0x0009 if word == 0x0008 else word for word in FRAME]
    packet, _ = decode(words)
    assert packet.frames[0].image.tolist() == EXPECTED_IMAGE
    assert packet.triggers.tolist()[0] == (16, TriggerKind.APS_FRAME_START)


@pytest.mark.parametrize(
    ("roi", "expected"),
    [
        ((340, 0, 349, 9), (0, 0, 9, 9)),  # runs past column 345: position becomes 0
        # end column before start: width <= 0 becomes the full 346, and 10 + 346 > 346 moves the
        # start to 0.
        ((10, 20, 5, 29), (0, 20, 345, 29)),
        ((0, 0, 345, 259), (0, 0, 345, 259)),  # full array unchanged
    ],
)
def test_roi_sanity_clamp(roi, expected):
    from davis_io.usb.assemble import FrameAssembler

    frames = FrameAssembler(SensorLayout())
    frames.start(0)
    for value in roi:
        frames.roi_byte(True, value >> 8)
        frames.roi_byte(False, value & 0xFF)
    assert frames.roi == expected


def test_any_split_point_gives_the_same_packets():
    words = [*FRAME, *IMU, 0x1003, 0x3004, 0x7002, 0x2005]
    data = le_bytes(words)
    whole, _ = decode(words)
    for cut in range(len(data) + 1):
        decoder = WordDecoder(SensorLayout())
        first, second = decoder.decode(data[:cut]), decoder.decode(data[cut:])
        assert np.concatenate([first.events, second.events]).tolist() == whole.events.tolist()
        frames = first.frames + second.frames
        assert len(frames) == 1 and frames[0].image.tolist() == EXPECTED_IMAGE
        assert len(first.imu) + len(second.imu) == 1
