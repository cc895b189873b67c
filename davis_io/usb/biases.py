"""Bias generator settings of DAVIS346 and DAVIS240 (module 5, params 0-127), with defaults."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

__all__ = [
    "Davis240Biases",
    "Davis346Biases",
    "bias_registers",
    "coarse_fine",
    "shifted_source",
    "vdac",
]


def coarse_fine(
    coarse: int,
    fine: int,
    *,
    n_type: bool,
    enabled: bool = True,
    cascode: bool = False,
    low_current: bool = False,
) -> int:
    """Register value of a coarse/fine current bias.

    Args:
        coarse: coarse range 0-7 (0 = 11 pA ... 7 = 24.8 µA full scale).
        fine: fine value 0-255 (fraction of the coarse range).
        n_type: True for an N-type transistor, False for P-type.
        enabled: bias on.
        cascode: cascode instead of normal type.
        low_current: low current level instead of normal.

    Returns:
        16-bit value: bit 0 enabled, 1 sex N, 2 type normal, 3 level normal, 4-11 fine,
        12-14 coarse.
    """
    return (
        int(enabled)
        | int(n_type) << 1
        | int(not cascode) << 2
        | int(not low_current) << 3
        | fine << 4
        | coarse << 12
    )


def vdac(voltage: int, current: int) -> int:
    """Register value of a voltage (VDAC) bias: bits 0-5 voltage (VDD/64), bits 6-8 current."""
    return voltage | current << 6


def shifted_source(ref: int, reg: int) -> int:
    """Register value of a shifted-source bias in shifted-source mode, split-gate level."""
    return ref << 4 | reg << 10


def _bias(param: int, value: int):
    return field(default=value, metadata={"param": param})


@dataclass(frozen=True)
class Davis346Biases:
    """DAVIS346 bias registers (37-branch generator), defaults as libcaer and DV send them."""

    aps_overflow_level: int = _bias(0, vdac(27, 6))
    aps_cas: int = _bias(1, vdac(21, 6))
    adc_ref_high: int = _bias(2, vdac(32, 7))
    adc_ref_low: int = _bias(3, vdac(1, 7))
    adc_test_voltage: int = _bias(4, vdac(21, 7))
    local_buf_bn: int = _bias(8, coarse_fine(5, 164, n_type=True))
    pad_foll_bn: int = _bias(9, coarse_fine(7, 215, n_type=True, enabled=False))
    diff_bn: int = _bias(10, coarse_fine(4, 39, n_type=True))
    on_bn: int = _bias(11, coarse_fine(5, 255, n_type=True))
    off_bn: int = _bias(12, coarse_fine(4, 1, n_type=True))
    pix_inv_bn: int = _bias(13, coarse_fine(6, 144, n_type=True))
    pr_bp: int = _bias(14, coarse_fine(2, 58, n_type=False))
    pr_sf_bp: int = _bias(15, coarse_fine(1, 16, n_type=False))
    refr_bp: int = _bias(16, coarse_fine(4, 25, n_type=False))
    readout_buf_bp: int = _bias(17, coarse_fine(6, 20, n_type=False))
    aps_ro_sf_bn: int = _bias(18, coarse_fine(6, 219, n_type=True))
    adc_comp_bp: int = _bias(19, coarse_fine(5, 20, n_type=False))
    col_sel_low_bn: int = _bias(20, coarse_fine(0, 1, n_type=True))
    dac_buf_bp: int = _bias(21, coarse_fine(6, 60, n_type=False))
    lcol_timeout_bn: int = _bias(22, coarse_fine(5, 49, n_type=True))
    ae_pd_bn: int = _bias(23, coarse_fine(6, 91, n_type=True))
    ae_pu_x_bp: int = _bias(24, coarse_fine(4, 80, n_type=False))
    ae_pu_y_bp: int = _bias(25, coarse_fine(7, 152, n_type=False))
    if_refr_bn: int = _bias(26, coarse_fine(5, 255, n_type=True))
    if_thr_bn: int = _bias(27, coarse_fine(5, 255, n_type=True))
    bias_buffer: int = _bias(34, coarse_fine(5, 254, n_type=True))
    ssp: int = _bias(35, shifted_source(1, 33))
    ssn: int = _bias(36, shifted_source(1, 33))


@dataclass(frozen=True)
class Davis240Biases:
    """DAVIS240 bias registers (22-branch generator), defaults as libcaer and DV send them."""

    diff_bn: int = _bias(0, coarse_fine(4, 39, n_type=True))
    on_bn: int = _bias(1, coarse_fine(5, 255, n_type=True))
    off_bn: int = _bias(2, coarse_fine(4, 0, n_type=True))
    aps_cas_epc: int = _bias(3, coarse_fine(5, 185, n_type=True, cascode=True))
    diff_cas_bnc: int = _bias(4, coarse_fine(5, 115, n_type=True, cascode=True))
    aps_ro_sf_bn: int = _bias(5, coarse_fine(6, 219, n_type=True))
    local_buf_bn: int = _bias(6, coarse_fine(5, 164, n_type=True))
    pix_inv_bn: int = _bias(7, coarse_fine(6, 144, n_type=True))
    pr_bp: int = _bias(8, coarse_fine(2, 58, n_type=False))
    pr_sf_bp: int = _bias(9, coarse_fine(1, 16, n_type=False))
    refr_bp: int = _bias(10, coarse_fine(4, 25, n_type=False))
    ae_pd_bn: int = _bias(11, coarse_fine(6, 91, n_type=True))
    lcol_timeout_bn: int = _bias(12, coarse_fine(5, 49, n_type=True))
    ae_pu_x_bp: int = _bias(13, coarse_fine(4, 80, n_type=False))
    ae_pu_y_bp: int = _bias(14, coarse_fine(7, 152, n_type=False))
    if_thr_bn: int = _bias(15, coarse_fine(5, 255, n_type=True))
    if_refr_bn: int = _bias(16, coarse_fine(5, 255, n_type=True))
    pad_foll_bn: int = _bias(17, coarse_fine(7, 215, n_type=True))
    aps_overflow_level_bn: int = _bias(18, coarse_fine(6, 253, n_type=True))
    bias_buffer: int = _bias(19, coarse_fine(5, 254, n_type=True))
    ssp: int = _bias(20, shifted_source(1, 33))
    ssn: int = _bias(21, shifted_source(1, 33))


def bias_registers(biases: Davis346Biases | Davis240Biases) -> list[tuple[int, int]]:
    """``(param, value)`` of every bias in parameter order (module 5)."""
    return [(item.metadata["param"], getattr(biases, item.name)) for item in fields(biases)]
