"""AEDAT 2.0 reader on records written by hand from davis-protocol.md §6.1."""

import numpy as np
import pytest

from davis_io.aedat import Aedat2Reader, open_recording
from davis_io.aedat.aedat2 import RECORD_DTYPE, Aedat2Decoder
from davis_io.aedat.report import RecordingWarning
from davis_io.errors import FormatError

HEADER = (
    b"#!AER-DAT2.0\r\n# This is a raw AE data file - do not edit\r\n"
    b"# AEChip: eu.seebetter.ini.chips.davis.Davis346B\r\n#End Of ASCII Header\r\n"
)

# Records: big-endian int32 address, int32 timestamp. DAVIS346: W = 346, H = 260.
DVS_AND_EXTERNAL = bytes.fromhex(
    # (x=0, y=0) ON: X field 345 (0x159 << 12 = 0x159000), Y field 259 (0x103 << 22 = 0x40C00000),
    # polarity bit 11 (0x800) -> 0x40D59800
    "40d59800"
    "0000000a"
    # (x=345, y=259) OFF: X field 0, Y field 0 -> 0x00000000
    "00000000"
    "0000000b"
    # (x=100, y=200) ON: X field 245 (0xF5000), Y field 59 (0x0EC00000), 0x800 -> 0x0ECF5800
    "0ecf5800"
    "0000000c"
    # external input: bit 10 set, kind 3 rising / 2 falling / 4 pulse
    "00000403"
    "00000014"
    "00000402"
    "00000015"
    "00000404"
    "00000016"
)
# IMU: 0x80000C00 | type << 28 | (value & 0xFFFF) << 12, seven records at the same time (30 µs).
IMU = bytes.fromhex(
    "81000c00"
    "0000001e"  # type 0 accel X = 4096
    "9f000c00"
    "0000001e"  # type 1 accel Y = -4096 (0xF000)
    "a0800c00"
    "0000001e"  # type 2 accel Z = 2048
    "b0154c00"
    "0000001e"  # type 3 temperature raw 340 (0x154)
    "c1000c00"
    "0000001e"  # type 4 gyro X = 4096
    "d8000c00"
    "0000001e"  # type 5 gyro Y = -32768 (0x8000)
    "e0000c00"
    "0000001e"  # type 6 gyro Z = 0
)
# APS on a 3 x 2 array: 0x80000000 | Y field << 22 | X field << 12 | readout << 10 | sample,
# X field = x, Y field = 1 - y. Reset reads (readout 0) at 100..150 µs, signal reads at 400..450.
APS_3X2 = bytes.fromhex(
    "80400258"
    "00000064"  # reset (0,0) = 600, first pixel: start of frame, 100
    "8040112c"
    "0000006e"  # reset (1,0) = 300 (< 384: saturated)
    "80402258"
    "00000078"  # reset (2,0) = 600
    "80000258"
    "00000082"  # reset (0,1) = 600
    "80001258"
    "0000008c"  # reset (1,1) = 600
    "80002258"
    "00000096"  # reset (2,1) = 600, last reset pixel: start of exposure, 150
    "80400464"
    "00000190"  # signal (0,0) = 100, first signal pixel: end of exposure, 400
    "80401432"
    "0000019a"  # signal (1,0) = 50
    "80402400"
    "000001a4"  # signal (2,0) = 0 (saturated)
    "800006bc"
    "000001ae"  # signal (0,1) = 700 (600 - 700 clamps to 0)
    "800014c8"
    "000001b8"  # signal (1,1) = 200
    "80002657"
    "000001c2"  # signal (2,1) = 599, last pixel: end of frame, 450
)


def _records(data):
    return np.frombuffer(data, dtype=RECORD_DTYPE)


def _read(tmp_path, body, header=HEADER, **options):
    path = tmp_path / "r.aedat"
    path.write_bytes(header + body)
    with open_recording(path, **options) as reader:
        return reader, list(reader)


def test_dvs_and_external_input_with_y_flip(tmp_path):
    reader, (packet,) = _read(tmp_path, DVS_AND_EXTERNAL)
    assert isinstance(reader, Aedat2Reader)
    assert (reader.info.camera, reader.info.width, reader.info.height) == ("DAVIS346", 346, 260)
    assert packet.events.tolist() == [(10, 0, 0, 1), (11, 345, 259, -1), (12, 100, 200, 1)]
    # rising edge 1, falling edge 2, pulse 3 (TriggerKind values)
    assert packet.triggers.tolist() == [(20, 1), (21, 2), (22, 3)]


def test_a_cut_record_ends_the_stream_and_says_where(tmp_path):
    # Six 8-byte records and 5 bytes of a seventh: the six are read, the cut is at 48.
    with pytest.warns(RecordingWarning, match=f"byte offset {len(HEADER) + 48}"):
        _, (packet,) = _read(tmp_path, DVS_AND_EXTERNAL + b"\x40\xd5\x98\x00\x00")
    assert len(packet.events) == 3 and len(packet.triggers) == 3
    assert packet.truncated_at == len(HEADER) + 48


def test_imu_sample_uses_jaer_default_scale(tmp_path):
    _, (packet,) = _read(tmp_path, IMU)
    (sample,) = packet.imu
    assert sample["t"] == 30
    # ±8 g: 4096 LSB/g; ±1000 deg/s: 32.768 LSB/(deg/s); T = raw / 340 + 35
    assert sample["acc_g"].tolist() == [1.0, -1.0, 0.5]
    assert sample["gyro_dps"].tolist() == [125.0, -1000.0, 0.0]
    assert sample["temperature_c"] == pytest.approx(36.0)


def test_imu_scale_from_header_preferences(tmp_path):
    preferences = (
        b'#<entry key="ImuAccelScale" value="ImuAccelScaleG2"/>\r\n'
        b'#<entry key="ImuGyroScale" value="GyroFullScaleDegPerSec250"/>\r\n'
    )
    header = HEADER.replace(b"#End", preferences + b"#End")
    _, (packet,) = _read(tmp_path, IMU, header=header)
    # ±2 g: 16384 LSB/g; ±250 deg/s: 131.072 LSB/(deg/s)
    assert packet.imu["acc_g"][0].tolist() == [0.25, -0.25, 0.125]
    assert packet.imu["gyro_dps"][0].tolist() == [31.25, -250.0, 0.0]


def test_imu_group_split_across_pieces_is_kept():
    decoder = Aedat2Decoder(346, 260)
    first = decoder.decode(_records(IMU[:24]))  # 3 of 7 records
    second = decoder.decode(_records(IMU[24:]))
    assert len(first.imu) == 0 and second.imu["acc_g"][0].tolist() == [1.0, -1.0, 0.5]


def test_aps_reads_become_a_frame_with_exposure_from_read_times():
    decoder = Aedat2Decoder(3, 2)
    (frame,) = decoder.decode(_records(APS_3X2)).frames
    assert (frame.readout_start_us, frame.exposure_start_us) == (100, 150)
    assert (frame.exposure_end_us, frame.readout_end_us) == (400, 450)
    assert frame.bit_depth == 10 and frame.image.dtype == np.uint16
    # reset - signal: 600-100; reset 300 < 384 -> 1023; signal 0 -> 1023; 600-700 -> 0; 400; 1
    assert frame.image.tolist() == [[500, 1023, 1023], [0, 400, 1]]


def test_aps_frame_split_across_pieces_and_davis240_gain():
    decoder = Aedat2Decoder(3, 2, adc_gain=2)
    assert decoder.decode(_records(APS_3X2[:56])).frames == []
    (frame,) = decoder.decode(_records(APS_3X2[56:])).frames
    # doubled reads: 1200-200; 600-100 (600 >= 384 now); signal 0 -> 1023; clamp 0; 800; 2
    assert frame.image.tolist() == [[1000, 500, 1023], [0, 800, 2]]


def test_incomplete_frame_is_dropped_with_a_note():
    decoder = Aedat2Decoder(3, 2)
    missing = APS_3X2[: 8 * 4] + APS_3X2[8 * 5 :]  # reset read of (1,1) lost
    with pytest.warns(UserWarning, match="incomplete"):
        packet = decoder.decode(_records(missing))
    assert packet.frames == [] and "incomplete" in packet.notes[0]


def test_timestamp_wrap_is_unwrapped():
    records = bytes.fromhex("00000000fffffffe0000000000000005")
    packet = Aedat2Decoder(346, 260).decode(_records(records))
    assert packet.events["t"].tolist() == [0xFFFFFFFE, (1 << 32) + 5]


def test_unknown_chip_needs_a_camera_option(tmp_path):
    header = HEADER.replace(b"eu.seebetter.ini.chips.davis.Davis346B", b"ch.unizh.ini.Tmpdiff128")
    with pytest.raises(FormatError, match="camera="):
        _read(tmp_path, DVS_AND_EXTERNAL, header=header)
    reader, (packet,) = _read(tmp_path, DVS_AND_EXTERNAL, header=header, camera="DAVIS346")
    assert packet.events["x"].tolist() == [0, 345, 100]


def test_header_without_end_marker_ends_at_first_non_hash_byte(tmp_path):
    header = HEADER.replace(b"#End Of ASCII Header\r\n", b"")
    _, (packet,) = _read(tmp_path, DVS_AND_EXTERNAL, header=header)
    assert len(packet.events) == 3
