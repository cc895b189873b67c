"""Numbers of the DAVIS USB protocol (logic 18): ids, requests, modules, parameters, codes."""

from __future__ import annotations

import enum

__all__ = [
    "BULK_IN_ENDPOINT",
    "CONFIG_READ_REQUEST_TYPE",
    "CONFIG_WRITE_REQUEST_TYPE",
    "DAVIS240_CHIP_IDS",
    "DAVIS346_CHIP_IDS",
    "FX2_PRODUCT_ID",
    "FX3_PRODUCT_ID",
    "INTERFACE",
    "MIN_FIRMWARE",
    "MIN_LOGIC_PATCH",
    "MULTI_WRITE_REQUEST",
    "REQUIRED_LOGIC_VERSION",
    "SINGLE_REQUEST",
    "TIMESTAMP_WRAP_US",
    "USB_CONFIGURATION",
    "VENDOR_ID",
    "Aps",
    "Chip",
    "ChipId",
    "Code",
    "Dvs",
    "ExtInput",
    "Imu",
    "Module",
    "Mux",
    "Special",
    "SysInfo",
    "Usb",
    "chip_name",
]

VENDOR_ID = 0x152A
FX3_PRODUCT_ID = 0x841A
"""FX3 boards, e.g. DAVIS346."""
FX2_PRODUCT_ID = 0x841B
"""FX2 boards, e.g. DAVIS240."""

USB_CONFIGURATION = 1
INTERFACE = 0
BULK_IN_ENDPOINT = 0x82

CONFIG_WRITE_REQUEST_TYPE = 0x40
"""OUT, vendor, device."""
CONFIG_READ_REQUEST_TYPE = 0xC0
"""IN, vendor, device."""
SINGLE_REQUEST = 0xBF
"""Read or write one 32-bit parameter (value big-endian)."""
MULTI_WRITE_REQUEST = 0xC2
"""Write N entries of ``[module:u8][param:u8][value:u32 big-endian]``; wValue = N."""

MIN_FIRMWARE = {FX3_PRODUCT_ID: 6, FX2_PRODUCT_ID: 4}
"""Minimum firmware version (low byte of bcdDevice) per product id."""
REQUIRED_LOGIC_VERSION = 18
MIN_LOGIC_PATCH = 1

TIMESTAMP_WRAP_US = 0x8000
"""One timestamp wrap: 2^15 µs."""


class Module(enum.IntEnum):
    """Configuration module addresses (wValue of 0xBF requests)."""

    MUX = 0
    DVS = 1
    APS = 2
    IMU = 3
    EXTINPUT = 4
    BIAS = 5
    SYSINFO = 6
    USB = 9


class Mux(enum.IntEnum):
    """MUX (module 0) parameters."""

    RUN = 0
    TIMESTAMP_RUN = 1
    TIMESTAMP_RESET = 2
    RUN_CHIP = 3
    DROP_EXTINPUT_ON_TRANSFER_STALL = 4
    DROP_DVS_ON_TRANSFER_STALL = 5
    HAS_STATISTICS = 80
    STATISTICS_EXTINPUT_DROPPED = 81
    STATISTICS_DVS_DROPPED = 83


class Dvs(enum.IntEnum):
    """DVS (module 1) parameters."""

    SIZE_COLUMNS = 0
    SIZE_ROWS = 1
    ORIENTATION_INFO = 2
    RUN = 3
    WAIT_ON_TRANSFER_STALL = 4
    EXTERNAL_AER_CONTROL = 5
    HAS_PIXEL_FILTER = 10
    FILTER_PIXEL_0_ROW = 11
    HAS_BACKGROUND_ACTIVITY_FILTER = 30
    FILTER_BACKGROUND_ACTIVITY = 31
    FILTER_BACKGROUND_ACTIVITY_TIME = 32
    FILTER_REFRACTORY_PERIOD = 33
    FILTER_REFRACTORY_PERIOD_TIME = 34
    HAS_ROI_FILTER = 40
    FILTER_ROI_START_COLUMN = 41
    FILTER_ROI_START_ROW = 42
    FILTER_ROI_END_COLUMN = 43
    FILTER_ROI_END_ROW = 44
    HAS_SKIP_FILTER = 50
    FILTER_SKIP_EVENTS = 51
    FILTER_SKIP_EVENTS_EVERY = 52
    HAS_POLARITY_FILTER = 60
    FILTER_POLARITY_FLATTEN = 61
    FILTER_POLARITY_SUPPRESS = 62
    FILTER_POLARITY_SUPPRESS_TYPE = 63
    HAS_STATISTICS = 80
    STATISTICS_DROPPED = 85


class Aps(enum.IntEnum):
    """APS (module 2) parameters."""

    SIZE_COLUMNS = 0
    SIZE_ROWS = 1
    ORIENTATION_INFO = 2
    COLOR_FILTER = 3
    RUN = 4
    WAIT_ON_TRANSFER_STALL = 5
    HAS_GLOBAL_SHUTTER = 6
    GLOBAL_SHUTTER = 7
    START_COLUMN_0 = 8
    START_ROW_0 = 9
    END_COLUMN_0 = 10
    END_ROW_0 = 11
    EXPOSURE = 12
    FRAME_INTERVAL = 13


class Imu(enum.IntEnum):
    """IMU (module 3) parameters."""

    TYPE = 0
    ORIENTATION_INFO = 1
    RUN_ACCELEROMETER = 2
    RUN_GYROSCOPE = 3
    RUN_TEMPERATURE = 4
    SAMPLE_RATE_DIVIDER = 5
    ACCEL_DLPF = 6
    ACCEL_FULL_SCALE = 7
    GYRO_DLPF = 9
    GYRO_FULL_SCALE = 10


class ExtInput(enum.IntEnum):
    """EXTINPUT (module 4) parameters."""

    RUN_DETECTOR = 0
    DETECT_RISING_EDGES = 1
    DETECT_FALLING_EDGES = 2
    DETECT_PULSES = 3
    DETECT_PULSE_POLARITY = 4
    DETECT_PULSE_LENGTH = 5
    HAS_GENERATOR = 10


class Chip(enum.IntEnum):
    """Chip configuration shift register (module 5, params 128-255)."""

    DIGITALMUX0 = 128
    ANALOGMUX0 = 132
    BIASMUX0 = 135
    RESETCALIBNEURON = 136
    TYPENCALIBNEURON = 137
    RESETTESTPIXEL = 138
    SPECIALPIXELCONTROL = 139
    AERNAROW = 140
    USEAOUT = 141
    GLOBAL_SHUTTER = 142
    SELECTGRAYCOUNTER = 143
    TESTADC = 144


class SysInfo(enum.IntEnum):
    """SYSINFO (module 6) read-only parameters."""

    LOGIC_VERSION = 0
    CHIP_IDENTIFIER = 1
    DEVICE_IS_MASTER = 2
    LOGIC_CLOCK = 3
    ADC_CLOCK = 4
    USB_CLOCK = 5
    CLOCK_DEVIATION = 6
    LOGIC_PATCH = 7


class Usb(enum.IntEnum):
    """USB (module 9) parameters."""

    RUN = 0
    EARLY_PACKET_DELAY = 1


class Code(enum.IntEnum):
    """Event-word codes (bits 14-12 of a word whose bit 15 is 0)."""

    SPECIAL = 0
    ROW = 1
    COLUMN_OFF = 2
    COLUMN_ON = 3
    APS_SAMPLE = 4
    MISC8 = 5
    MISC10 = 6
    WRAP = 7


class Special(enum.IntEnum):
    """Device special-event codes (data of a code-0 word), logic 18."""

    RESERVED = 0
    TIMESTAMP_RESET = 1
    EXTERNAL_INPUT_FALLING_EDGE = 2
    EXTERNAL_INPUT_RISING_EDGE = 3
    EXTERNAL_INPUT_PULSE = 4
    IMU_START = 5
    UNUSED_6 = 6
    IMU_END = 7
    APS_FRAME_START_GLOBAL = 8
    APS_FRAME_START_ROLLING = 9
    APS_FRAME_END = 10
    APS_RESET_COLUMN_START = 11
    APS_SIGNAL_COLUMN_START = 12
    APS_COLUMN_END = 13
    APS_EXPOSURE_START = 14
    APS_EXPOSURE_END = 15
    EXTERNAL_GENERATOR_FALLING_EDGE = 16
    EXTERNAL_GENERATOR_RISING_EDGE = 17


class ChipId(enum.IntEnum):
    """SYSINFO chip identifiers."""

    DAVIS240A = 0
    DAVIS240B = 1
    DAVIS240C = 2
    DAVIS128 = 3
    DAVIS346A = 4
    DAVIS346B = 5
    DAVIS640 = 6
    DAVIS640H = 7
    DAVIS208 = 8
    DAVIS346C = 9


DAVIS346_CHIP_IDS = frozenset({ChipId.DAVIS346A, ChipId.DAVIS346B, ChipId.DAVIS346C})
DAVIS240_CHIP_IDS = frozenset({ChipId.DAVIS240A, ChipId.DAVIS240B, ChipId.DAVIS240C})


def chip_name(chip_id: int) -> str:
    """Return the camera model name of a SYSINFO chip id (``"DAVIS346"`` for every 346 variant)."""
    if chip_id in DAVIS346_CHIP_IDS:
        return "DAVIS346"
    if chip_id in DAVIS240_CHIP_IDS:
        return "DAVIS240"
    try:
        return ChipId(chip_id).name
    except ValueError:
        return f"unknown chip {chip_id}"
