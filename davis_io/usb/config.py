"""Typed DAVIS configuration with spec defaults, its registers and the writes a change needs."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from davis_io.errors import UsageError
from davis_io.usb.biases import Davis240Biases, Davis346Biases, bias_registers
from davis_io.usb.layout import SensorLayout
from davis_io.usb.protocol import Aps, Chip, Dvs, ExtInput, Imu, Module, Mux, Usb

__all__ = [
    "ApsConfig",
    "DavisConfig",
    "DeviceFacts",
    "DvsConfig",
    "ImuConfig",
    "RegisterWrite",
    "UsbConfig",
    "config_registers",
    "config_writes",
    "with_chip_biases",
]

RegisterWrite = tuple[int, int, int]
"""``(module, parameter, value)`` of one 32-bit configuration write."""

_PIXEL_FILTER_SLOTS = 8


def _check_range(owner: object, name: str, low: int, high: int, unit: str = "") -> None:
    value = getattr(owner, name)
    if not low <= value <= high:
        raise UsageError(
            f"{type(owner).__name__}.{name} = {value}{unit} is out of range; "
            f"use {low}..{high}{unit}"
        )


@dataclass(frozen=True)
class DeviceFacts:
    """What the device reported at open time (info registers and SYSINFO).

    Attributes:
        layout: array sizes and orientation.
        chip_id: SYSINFO chip identifier.
        logic_clock_mhz: actual logic clock (integer clock x deviation / 1000), MHz.
        adc_clock_mhz: actual ADC clock, MHz.
        usb_clock_mhz: actual USB clock, MHz.
        has_global_shutter: APS HAS_GLOBAL_SHUTTER.
        has_dvs_filters: DVS HAS_PIXEL_FILTER, HAS_BACKGROUND_ACTIVITY_FILTER, HAS_ROI_FILTER,
            HAS_SKIP_FILTER, HAS_POLARITY_FILTER all set (DAVIS346 logic 18 has them).
        has_statistics: MUX HAS_STATISTICS (drop counters readable).
    """

    layout: SensorLayout
    chip_id: int
    logic_clock_mhz: float
    adc_clock_mhz: float
    usb_clock_mhz: float
    has_global_shutter: bool = True
    has_dvs_filters: bool = True
    has_statistics: bool = True

    @property
    def is_davis240(self) -> bool:
        """True for the DAVIS240 family (22-branch biases, no gray counter or test ADC)."""
        return self.chip_id in (0, 1, 2)


@dataclass(frozen=True)
class DvsConfig:
    """DVS filters (module 1). Times in units of 250 µs, as the device takes them."""

    background_activity_filter: bool = True
    """Drop events without a recent neighbour."""
    background_activity_time_250us: int = 8
    """Neighbour support window, 250 µs units (8 = 2 ms)."""
    refractory_filter: bool = False
    """Drop events of a pixel that fired recently."""
    refractory_time_250us: int = 1
    """Refractory window, 250 µs units."""
    skip_events: bool = False
    """Drop one event every ``skip_every``."""
    skip_every: int = 5
    polarity_flatten: bool = False
    polarity_suppress: bool = False
    polarity_suppress_type: int = 0
    """0 suppresses OFF, 1 suppresses ON."""

    def __post_init__(self):
        _check_range(self, "background_activity_time_250us", 0, 4095)
        _check_range(self, "refractory_time_250us", 0, 4095)
        _check_range(self, "skip_every", 0, 255)
        _check_range(self, "polarity_suppress_type", 0, 1)


@dataclass(frozen=True)
class ApsConfig:
    """Frame readout (module 2). Exposure and interval in µs; auto-exposure is never used."""

    exposure_us: int = 4000
    """Exposure, 0-4194303 µs."""
    frame_interval_us: int = 40000
    """Time between frame starts, 0-8388607 µs (40000 = 25 frames/s)."""
    global_shutter: bool = True
    """Global shutter where the chip has one (ignored otherwise)."""
    wait_on_transfer_stall: bool = True
    """Stall the readout instead of losing pixels when USB is congested (complete frames)."""

    def __post_init__(self):
        _check_range(self, "exposure_us", 0, 4_194_303, " µs")
        _check_range(self, "frame_interval_us", 0, 8_388_607, " µs")


@dataclass(frozen=True)
class ImuConfig:
    """IMU (module 3). Full scales: accel 0-3 = ±2/4/8/16 g, gyro 0-3 = ±250/500/1000/2000 °/s."""

    sample_rate_divider: int = 0
    accel_dlpf: int = 1
    accel_full_scale: int = 1
    gyro_dlpf: int = 1
    """MPU-9250 only."""
    gyro_full_scale: int = 1

    def __post_init__(self):
        _check_range(self, "sample_rate_divider", 0, 255)
        for name in ("accel_dlpf", "gyro_dlpf"):
            _check_range(self, name, 0, 7)
        for name in ("accel_full_scale", "gyro_full_scale"):
            _check_range(self, name, 0, 3)


@dataclass(frozen=True)
class UsbConfig:
    """USB FIFO (module 9)."""

    early_packet_delay_125us: int = 8
    """Commit a short USB packet after this many 125 µs slices (8 = 1 ms)."""


@dataclass(frozen=True)
class DavisConfig:
    """Everything the host sets on a DAVIS, with the defaults libcaer sends."""

    dvs: DvsConfig = field(default_factory=DvsConfig)
    aps: ApsConfig = field(default_factory=ApsConfig)
    imu: ImuConfig = field(default_factory=ImuConfig)
    usb: UsbConfig = field(default_factory=UsbConfig)
    biases: Davis346Biases | Davis240Biases | None = None
    """None selects the chip's default biases."""


def with_chip_biases(config: DavisConfig, facts: DeviceFacts) -> DavisConfig:
    """``config`` with ``biases`` filled in with the chip's defaults when it is None."""
    if config.biases is not None:
        return config
    return replace(config, biases=Davis240Biases() if facts.is_davis240 else Davis346Biases())


def _chip_registers(config: DavisConfig, facts: DeviceFacts) -> list[RegisterWrite]:
    chip = [(Chip.DIGITALMUX0 + i, 0) for i in range(4)]
    chip += [(Chip.ANALOGMUX0 + i, 0) for i in range(3)]
    chip += [
        (Chip.BIASMUX0, 0),
        (Chip.RESETCALIBNEURON, 1),
        (Chip.TYPENCALIBNEURON, 0),
        (Chip.RESETTESTPIXEL, 1),
    ]
    if facts.is_davis240:
        chip.append((Chip.SPECIALPIXELCONTROL, 0))
    chip += [(Chip.AERNAROW, 0), (Chip.USEAOUT, 0)]
    if facts.has_global_shutter:
        chip.append((Chip.GLOBAL_SHUTTER, int(config.aps.global_shutter)))
    if not facts.is_davis240:
        chip += [(Chip.SELECTGRAYCOUNTER, 1), (Chip.TESTADC, 0)]
    biases = with_chip_biases(config, facts).biases
    return [(Module.BIAS, p, v) for p, v in bias_registers(biases) + chip]


def _dvs_registers(dvs: DvsConfig, facts: DeviceFacts) -> list[RegisterWrite]:
    writes = [(Dvs.WAIT_ON_TRANSFER_STALL, 0), (Dvs.EXTERNAL_AER_CONTROL, 0)]
    if facts.has_dvs_filters:
        columns, rows = facts.layout.dvs_columns, facts.layout.dvs_rows
        for slot in range(_PIXEL_FILTER_SLOTS):
            writes += [
                (Dvs.FILTER_PIXEL_0_ROW + 2 * slot, rows),
                (Dvs.FILTER_PIXEL_0_ROW + 2 * slot + 1, columns),
            ]
        writes += [
            (Dvs.FILTER_BACKGROUND_ACTIVITY, int(dvs.background_activity_filter)),
            (Dvs.FILTER_BACKGROUND_ACTIVITY_TIME, dvs.background_activity_time_250us),
            (Dvs.FILTER_REFRACTORY_PERIOD, int(dvs.refractory_filter)),
            (Dvs.FILTER_REFRACTORY_PERIOD_TIME, dvs.refractory_time_250us),
            (Dvs.FILTER_ROI_START_COLUMN, 0),
            (Dvs.FILTER_ROI_START_ROW, 0),
            (Dvs.FILTER_ROI_END_COLUMN, columns - 1),
            (Dvs.FILTER_ROI_END_ROW, rows - 1),
            (Dvs.FILTER_SKIP_EVENTS, int(dvs.skip_events)),
            (Dvs.FILTER_SKIP_EVENTS_EVERY, dvs.skip_every),
            (Dvs.FILTER_POLARITY_FLATTEN, int(dvs.polarity_flatten)),
            (Dvs.FILTER_POLARITY_SUPPRESS, int(dvs.polarity_suppress)),
            (Dvs.FILTER_POLARITY_SUPPRESS_TYPE, dvs.polarity_suppress_type),
        ]
    return [(Module.DVS, p, v) for p, v in writes]


def _aps_registers(aps: ApsConfig, facts: DeviceFacts) -> list[RegisterWrite]:
    writes = [(Aps.WAIT_ON_TRANSFER_STALL, int(aps.wait_on_transfer_stall))]
    if facts.has_global_shutter:
        writes.append((Aps.GLOBAL_SHUTTER, int(aps.global_shutter)))
    writes += [
        (Aps.START_COLUMN_0, 0),
        (Aps.START_ROW_0, 0),
        (Aps.END_COLUMN_0, facts.layout.aps_columns - 1),
        (Aps.END_ROW_0, facts.layout.aps_rows - 1),
        (Aps.EXPOSURE, round(aps.exposure_us * facts.adc_clock_mhz)),
        (Aps.FRAME_INTERVAL, round(aps.frame_interval_us * facts.adc_clock_mhz)),
    ]
    return [(Module.APS, p, v) for p, v in writes]


def _imu_registers(imu: ImuConfig, facts: DeviceFacts) -> list[RegisterWrite]:
    writes = [
        (Imu.SAMPLE_RATE_DIVIDER, imu.sample_rate_divider),
        (Imu.ACCEL_DLPF, imu.accel_dlpf),
        (Imu.ACCEL_FULL_SCALE, imu.accel_full_scale),
    ]
    if facts.layout.imu_type == 2:
        writes.append((Imu.GYRO_DLPF, imu.gyro_dlpf))
    writes.append((Imu.GYRO_FULL_SCALE, imu.gyro_full_scale))
    return [(Module.IMU, p, v) for p, v in writes]


def config_registers(config: DavisConfig, facts: DeviceFacts) -> list[RegisterWrite]:
    """Every register of ``config`` in the order libcaer sends its defaults.

    Order: biases, chip configuration, MUX, DVS, APS, IMU, external input, USB early packet
    delay. Times are converted with the device clocks: APS exposure and interval with the ADC
    clock, the pulse length with the logic clock, the early packet delay with the USB clock.
    """
    mux = [
        (Module.MUX, Mux.TIMESTAMP_RESET, 0),
        (Module.MUX, Mux.DROP_EXTINPUT_ON_TRANSFER_STALL, 1),
        (Module.MUX, Mux.DROP_DVS_ON_TRANSFER_STALL, 1),
    ]
    extinput = [
        (ExtInput.DETECT_RISING_EDGES, 0),
        (ExtInput.DETECT_FALLING_EDGES, 0),
        (ExtInput.DETECT_PULSES, 1),
        (ExtInput.DETECT_PULSE_POLARITY, 1),
        (ExtInput.DETECT_PULSE_LENGTH, round(10 * facts.logic_clock_mhz)),
    ]
    delay = round(config.usb.early_packet_delay_125us * 125 * facts.usb_clock_mhz)
    return [
        *_chip_registers(config, facts),
        *mux,
        *_dvs_registers(config.dvs, facts),
        *_aps_registers(config.aps, facts),
        *_imu_registers(config.imu, facts),
        *[(Module.EXTINPUT, p, v) for p, v in extinput],
        (Module.USB, Usb.EARLY_PACKET_DELAY, delay),
    ]


def config_writes(old: DavisConfig | None, new: DavisConfig, facts: DeviceFacts):
    """The writes that take the device from ``old`` to ``new`` (all of them when ``old`` is None).

    Returns:
        list of ``RegisterWrite`` in :func:`config_registers` order, only those whose value differs.
    """
    before = {} if old is None else {(m, p): v for m, p, v in config_registers(old, facts)}
    return [(m, p, v) for m, p, v in config_registers(new, facts) if before.get((m, p)) != v]
