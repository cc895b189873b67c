"""AEDAT 3.1 reader on packets written by hand from davis-protocol.md §6.2."""

import numpy as np
import pytest

from davis_io.aedat import Aedat31Reader, RecordingWarning, open_recording

HEADER = (
    b"#!AER-DAT3.1\r\n#Format: RAW\r\n#Source 1: DAVIS346\r\n"
    b"#Start-Time: 2020-01-01 00:00:00 (TZ+0000)\r\n#!END-HEADER\r\n"
)


def packet_header(event_type, size, ts_offset, overflow, capacity, valid):
    """28-byte header, little-endian: int16 type, int16 source=1, then six int32."""
    return (
        event_type.to_bytes(2, "little")
        + (1).to_bytes(2, "little")
        + b"".join(
            v.to_bytes(4, "little", signed=True)
            for v in (size, ts_offset, overflow, capacity, capacity, valid)
        )
    )


# Polarity: uint32 data (bit 0 valid, bit 1 ON, bits 2-16 y, bits 17-31 x), int32 ts.
POLARITY = packet_header(1, 8, 4, 1, 3, 2) + bytes.fromhex(
    # x=345 (0x159<<17 = 0x02B20000), y=259 (0x103<<2 = 0x40C), ON (2), valid (1) -> 0x02B2040F
    "0f04b202"
    "e8030000"  # ts 1000
    # x=0, y=0, OFF, valid -> 0x00000001
    "01000000"
    "e9030000"  # ts 1001
    # not valid (bit 0 clear) -> skipped
    "02000000"
    "ea030000"  # ts 1002
)
# Special: bit 0 valid, bits 1-7 libcaer type.
SPECIAL = packet_header(0, 8, 4, 0, 4, 4) + bytes.fromhex(
    "1d000000"
    "f4010000"  # type 14 APS_FRAME_START: 1 | 14<<1 = 0x1D, ts 500 -> kind 6
    "05000000"
    "58020000"  # type 2 EXTERNAL_INPUT_RISING_EDGE: 1 | 2<<1 = 5, ts 600 -> kind 1
    "0b000000"
    "bc020000"  # type 5 DVS_ROW_ONLY: 1 | 5<<1 = 0x0B, ts 700 -> dropped
    "03000000"
    "20030000"  # type 1 TIMESTAMP_RESET: 1 | 1<<1 = 3, ts 800 -> kind 0
)
# IMU6: info, ts, accel x/y/z (g), gyro x/y/z (deg/s), temperature (°C), float32 LE.
IMU6 = packet_header(3, 36, 4, 0, 1, 1) + bytes.fromhex(
    "01000000"
    "d0070000"  # valid, ts 2000
    "0000003f"
    "000080bf"
    "0000803e"  # 0.5, -1.0, 0.25 g
    "00002041"
    "0000a0c1"
    "00000000"  # 10.0, -20.0, 0.0 deg/s
    "0000de41"  # 27.75 °C = 1.734375 * 2^4 -> 0x41DE0000
)
# Frame: 36-byte header + 3 x 2 pixels of 16-bit normalized (10-bit << 6); overflow 2.
FRAME = packet_header(2, 36 + 6 * 2, 8, 2, 1, 1) + bytes.fromhex(
    "03000000"  # valid, 1 channel (1 << 1)
    "64000000"
    "84030000"
    "2c010000"
    "bc020000"  # SOF 100, EOF 900, SOE 300, EOE 700
    "03000000"
    "02000000"
    "04000000"
    "05000000"  # lengthX 3, lengthY 2, positionX 4, positionY 5
    "0000"
    "4000"
    "c0ff"  # row 0: 0, 1 << 6 = 0x40, 1023 << 6 = 0xFFC0
    "0080"
    "0060"
    "0019"  # row 1: 512 << 6 = 0x8000, 384 << 6 = 0x6000, 100 << 6 = 0x1900
)


def _read(tmp_path, body):
    path = tmp_path / "r.aedat"
    path.write_bytes(HEADER + body)
    with open_recording(path) as reader:
        return reader, list(reader)


def test_every_event_kind_decodes_to_hand_computed_values(tmp_path):
    reader, packets = _read(tmp_path, POLARITY + SPECIAL + IMU6 + FRAME)
    assert isinstance(reader, Aedat31Reader)
    assert (reader.info.camera, reader.info.width, reader.info.height) == ("DAVIS346", 346, 260)
    assert len(packets) == 4
    events = packets[0].events
    # overflow 1: t = 1 << 31 | ts = 2147483648 + ts
    assert events.tolist() == [(2147484648, 345, 259, 1), (2147484649, 0, 0, -1)]
    assert packets[1].triggers.tolist() == [(500, 6), (600, 1), (800, 0)]
    (sample,) = packets[2].imu
    assert sample["t"] == 2000 and sample["temperature_c"] == 27.75
    assert sample["acc_g"].tolist() == [0.5, -1.0, 0.25]
    assert sample["gyro_dps"].tolist() == [10.0, -20.0, 0.0]
    (frame,) = packets[3].frames
    base = 2 << 31  # overflow 2
    assert (frame.readout_start_us, frame.exposure_start_us) == (base + 100, base + 300)
    assert (frame.exposure_end_us, frame.readout_end_us) == (base + 700, base + 900)
    assert frame.exposure_us == 400 and frame.position == (4, 5) and frame.bit_depth == 10
    assert frame.image.dtype == np.uint16
    assert frame.image.tolist() == [[0, 1, 1023], [512, 384, 100]]


def test_unknown_event_type_is_skipped_with_a_warning(tmp_path):
    spike = packet_header(12, 8, 4, 0, 1, 1) + bytes(8)  # type 12 (spike) is not read
    with pytest.warns(RecordingWarning, match="event type 12"):
        _, packets = _read(tmp_path, spike + POLARITY)
    assert packets[0].is_empty and "event type 12" in packets[0].notes[0]
    assert len(packets[1].events) == 2


def test_truncated_packet_keeps_its_complete_events(tmp_path):
    cut = len(HEADER) + len(SPECIAL) + 28 + 8 + 5  # one polarity event and 5 bytes of the next
    path = tmp_path / "t.aedat"
    path.write_bytes((HEADER + SPECIAL + POLARITY)[:cut])
    with pytest.warns(RecordingWarning, match=f"byte offset {len(HEADER) + len(SPECIAL)}"):
        with open_recording(path) as reader:
            packets = list(reader)
    assert packets[1].events.tolist() == [(2147484648, 345, 259, 1)]
    assert "truncated" in packets[1].notes[0]
    assert packets[0].truncated_at is None
    assert packets[1].truncated_at == len(HEADER) + len(SPECIAL)
