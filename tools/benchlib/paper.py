"""The paper's published numbers for the comparisons we rerun, and the orderings they claim."""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

__all__ = ["COMPARISONS", "Claim", "Comparison", "paper_claims"]


@dataclass(frozen=True)
class Comparison:
    """One of the paper's comparisons, rerun on our data.

    Attributes:
        key: short identifier used in ``results.json``.
        title: heading in the report.
        columns: the paper's columns (datasets), in the order claims prefer them.
        rows: our row key (a variant name or a condition) -> paper label and, per column,
            ``(PSNR dB, SSIM)`` or None where the paper reports nothing.
        axis: ``variant`` (rows are variants on one session) or ``session`` (rows are sessions
            fitted with one variant).
        ours: how the comparison is set up on our data (one sentence for the report).
    """

    key: str
    title: str
    columns: tuple[str, ...]
    rows: dict[str, tuple[str, tuple[tuple[float, float] | None, ...]]]
    axis: str = "variant"
    ours: str = "Each row is that variant fitted on the main session."


@dataclass(frozen=True)
class Claim:
    """The paper reports ``better`` above ``worse`` in HDR PSNR on ``column``."""

    better: str
    worse: str
    column: str
    better_db: float
    worse_db: float


# Table 3 of the paper (ablation); columns: our synthetic data (HDR), our real data (HDR),
# Real-World-Challenge data (deblurring). See-NeRF^Base is reported on the last one only.
TABLE_3 = Comparison(
    "table3",
    "Table 3: ablation",
    ("synthetic HDR", "real HDR", "Real-World-Challenge"),
    {
        "base": ("See-NeRF^Base", (None, None, (28.79, 0.9201))),
        "no-events": ("See-NeRF^NoEv", ((22.19, 0.8361), (19.84, 0.7881), (30.22, 0.9350))),
        "naive-events": ("See-NeRF^NoEM", ((22.23, 0.8682), (25.87, 0.8867), (32.47, 0.9547))),
        "point-crf-3d": ("See-NeRF^3D", ((20.67, 0.8561), (24.95, 0.8323), (31.58, 0.9534))),
        "evdeblur-ecrf": ("See-NeRF^EvD", ((22.02, 0.8669), (16.43, 0.6932), (29.52, 0.9267))),
        "full": ("See-NeRF", ((24.13, 0.8927), (26.49, 0.8953), (32.70, 0.9564))),
    },
)

# Supplementary Table 9 (earlier CRF models), upper half: the RGB CRF. Columns: our real data
# (HDR), Real-World-Challenge data.
TABLE_9_CRF = Comparison(
    "table9-crf",
    "Table 9: RGB CRF models",
    ("real HDR", "Real-World-Challenge"),
    {
        "power-crf": ("See-NeRF^Pow", ((19.75, 0.7239), (28.35, 0.9242))),
        "full": ("See-NeRF", ((26.49, 0.8953), (32.70, 0.9564))),
    },
)

# Supplementary Table 9, lower half: the event low-pass (delay) model. The paper prints the
# Deblur-e real-data SSIM as "8859", read here as .8859.
TABLE_9_LOWPASS = Comparison(
    "table9-lowpass",
    "Table 9: event low-pass models",
    ("real HDR", "Real-World-Challenge"),
    {
        "v2e-lowpass": ("See-NeRF^v2e", ((22.10, 0.8644), (30.51, 0.9441))),
        "deblur-e-lowpass": ("See-NeRF^Deblur-e", ((24.28, 0.8859), (31.84, 0.9521))),
        "full": ("See-NeRF", ((26.49, 0.8953), (32.70, 0.9564))),
    },
)

# Table 4 of the paper, left half: input exposure 0.001 s, 0.016 s, 0.256 s on the synthetic
# "Catroom" scene (HDR).
TABLE_4_EXPOSURE = Comparison(
    "table4-exposure",
    "Table 4: input exposure",
    ("synthetic HDR (Catroom)",),
    {
        "exposure-x1/16": ("0.001 s", ((24.66, 0.8886),)),
        "exposure-x1": ("0.016 s", ((25.08, 0.8956),)),
        "exposure-x16": ("0.256 s", ((25.68, 0.9062),)),
    },
    axis="session",
    ours="Each row is `full` fitted on a room session filmed at 0.001, 0.016 or 0.256 s with the "
    "sensor gain of 0.016 s (shorter is darker, longer clips), as the paper's sweep.",
)

# Table 4 of the paper, right half: event noise x1, x2, x4 on the same scene (HDR).
TABLE_4_NOISE = Comparison(
    "table4-noise",
    "Table 4: event noise",
    ("synthetic HDR (Catroom)",),
    {
        "noise-x1": ("x1", ((25.08, 0.8956),)),
        "noise-x2": ("x2", ((24.99, 0.8956),)),
        "noise-x4": ("x4", ((24.86, 0.8948),)),
    },
    axis="session",
    ours="Each row is `full` fitted on a 0.016 s room session whose DVS leak and shot-noise rates "
    "(0.01 Hz and 0.001 Hz per pixel in the benchmark's `noisy` pixel model) are x1, x2, x4.",
)

COMPARISONS: tuple[Comparison, ...] = (
    TABLE_3,
    TABLE_9_CRF,
    TABLE_9_LOWPASS,
    TABLE_4_EXPOSURE,
    TABLE_4_NOISE,
)
"""Every comparison of the report, in report order."""


def paper_claims(comparison: Comparison) -> list[Claim]:
    """Every strict HDR PSNR ordering the paper reports between two rows.

    For each pair of rows the first column (in ``comparison.columns`` order) where both have a
    number decides; pairs with no common column or equal PSNR make no claim.
    """
    claims = []
    for first, second in combinations(comparison.rows, 2):
        for index, column in enumerate(comparison.columns):
            a = comparison.rows[first][1][index]
            b = comparison.rows[second][1][index]
            if a is None or b is None:
                continue
            if not math.isclose(a[0], b[0]):
                better, worse = (first, second) if a[0] > b[0] else (second, first)
                claims.append(Claim(better, worse, column, max(a[0], b[0]), min(a[0], b[0])))
            break
    return claims
