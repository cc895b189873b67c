"""Configuration: bias encodings, register list, clock conversion and change diffs."""

import pytest

from davis_io.errors import UsageError
from davis_io.usb.biases import Davis240Biases, Davis346Biases, bias_registers, coarse_fine, vdac
from davis_io.usb.config import (
    ApsConfig,
    DavisConfig,
    DeviceFacts,
    DvsConfig,
    ImuConfig,
    config_registers,
    config_writes,
)
from davis_io.usb.layout import SensorLayout

FACTS = DeviceFacts(
    SensorLayout(), chip_id=5, logic_clock_mhz=90.0, adc_clock_mhz=30.0, usb_clock_mhz=30.0
)

# davis-protocol.md §2.5 DAVIS346 table, register column.
SPEC_346 = {
    0: 0x019B,
    1: 0x0195,
    2: 0x01E0,
    3: 0x01C1,
    4: 0x01D5,
    8: 0x5A4F,
    9: 0x7D7E,
    10: 0x427F,
    11: 0x5FFF,
    12: 0x401F,
    13: 0x690F,
    14: 0x23AD,
    15: 0x110D,
    16: 0x419D,
    17: 0x614D,
    18: 0x6DBF,
    19: 0x514D,
    20: 0x001F,
    21: 0x63CD,
    22: 0x531F,
    23: 0x65BF,
    24: 0x450D,
    25: 0x798D,
    26: 0x5FFF,
    27: 0x5FFF,
    34: 0x5FEF,
    35: 0x8410,
    36: 0x8410,
}
SPEC_240 = {
    0: 0x427F,
    1: 0x5FFF,
    2: 0x400F,
    3: 0x5B9B,
    4: 0x573B,
    5: 0x6DBF,
    6: 0x5A4F,
    7: 0x690F,
    8: 0x23AD,
    9: 0x110D,
    10: 0x419D,
    11: 0x65BF,
    12: 0x531F,
    13: 0x450D,
    14: 0x798D,
    15: 0x5FFF,
    16: 0x5FFF,
    17: 0x7D7F,
    18: 0x6FDF,
    19: 0x5FEF,
    20: 0x8410,
    21: 0x8410,
}


def test_bias_encodings_by_hand():
    # OnBn N 5/255: enabled 1 | N 2 | normal 4 | level 8 = 0xF; fine 255 << 4 = 0xFF0;
    # coarse 5 << 12 = 0x5000 -> 0x5FFF.
    assert coarse_fine(5, 255, n_type=True) == 0x5FFF
    # VDAC V 27 I 6: 27 | 6 << 6 = 27 + 384 = 411 = 0x019B.
    assert vdac(27, 6) == 0x019B


def test_default_biases_match_the_spec_tables():
    assert dict(bias_registers(Davis346Biases())) == SPEC_346
    assert dict(bias_registers(Davis240Biases())) == SPEC_240


def test_times_go_through_the_clocks():
    regs = {(m, p): v for m, p, v in config_registers(DavisConfig(), FACTS)}
    assert regs[(2, 12)] == 4000 * 30  # exposure 4000 µs x 30 MHz ADC clock
    assert regs[(2, 13)] == 40000 * 30  # frame interval
    assert regs[(9, 1)] == 8 * 125 * 30  # early packet delay: 8 slices of 125 µs, USB clock
    assert regs[(4, 5)] == 10 * 90  # pulse length 10 µs, logic clock
    assert regs[(2, 7)] == 1 and regs[(5, 142)] == 1  # global shutter, both registers


def test_deviation_scaled_clock_rounds():
    facts = DeviceFacts(SensorLayout(), 5, 90.0, 30.0 * 1.001, 30.0)
    regs = {
        (m, p): v
        for m, p, v in config_registers(DavisConfig(aps=ApsConfig(exposure_us=333)), facts)
    }
    assert regs[(2, 12)] == round(333 * 30.03)  # 9999.99 -> 10000


def test_no_global_shutter_register_without_the_feature():
    facts = DeviceFacts(SensorLayout(), 5, 90.0, 30.0, 30.0, has_global_shutter=False)
    keys = {(m, p) for m, p, _ in config_registers(DavisConfig(), facts)}
    assert (2, 7) not in keys and (5, 142) not in keys


def test_first_configuration_writes_everything_then_only_changes():
    assert config_writes(None, DavisConfig(), FACTS) == config_registers(DavisConfig(), FACTS)
    assert config_writes(DavisConfig(), DavisConfig(), FACTS) == []
    new = DavisConfig(
        aps=ApsConfig(exposure_us=150_000, global_shutter=False),
        dvs=DvsConfig(refractory_filter=True),
    )
    # Order follows the register list: chip (5/142) first, then DVS, then APS.
    assert config_writes(DavisConfig(), new, FACTS) == [
        (5, 142, 0),
        (1, 33, 1),
        (2, 7, 0),
        (2, 12, 4_500_000),
    ]


def test_davis240_has_no_gray_counter_and_its_own_biases():
    facts = DeviceFacts(SensorLayout(240, 180, False, 240, 180), 2, 90.0, 30.0, 30.0)
    regs = {(m, p): v for m, p, v in config_registers(DavisConfig(), facts)}
    assert (5, 143) not in regs and (5, 144) not in regs
    assert regs[(5, 17)] == 0x7D7F
    assert regs[(1, 11)] == 180 and regs[(1, 12)] == 240  # pixel filter slot 0 disabled


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: ApsConfig(exposure_us=4_194_304),
            r"ApsConfig.exposure_us = 4194304 µs .* 0..4194303",
        ),
        (lambda: ApsConfig(frame_interval_us=-1), "ApsConfig.frame_interval_us = -1 µs"),
        (lambda: ImuConfig(accel_full_scale=4), "ImuConfig.accel_full_scale = 4 is out of range"),
        (lambda: DvsConfig(refractory_time_250us=4096), "refractory_time_250us = 4096"),
    ],
)
def test_out_of_range_settings_are_refused(make, message):
    with pytest.raises(UsageError, match=message):
        make()
