"""The paper's method and its comparisons as named variants: one table, no if/else on names."""

from __future__ import annotations

from dataclasses import dataclass, field

from seenerf.errors import ConfigError
from seenerf.sensors.event_crf import EventModelSpec

__all__ = ["LOW_PASS_READINGS", "VARIANTS", "Variant", "get_variant"]


@dataclass(frozen=True)
class Variant:
    """What is supervised and how the sensors are modelled.

    Attributes:
        description: one line for ``--help`` and reports.
        imaging: ``pixel`` (blur in linear HDR, then the RGB CRF per pixel: the paper),
            ``point`` (CRF on every 3-D sample, blur in LDR: HDR-NeRF style) or ``ldr-field``
            (the field renders LDR directly, blur in LDR, no CRF).
        crf: ``mlp`` (three per-channel MLPs), ``power`` (x^a), ``true`` (the truth's table,
            the oracle) or ``none``.
        events: the event model, or None for no event loss.
        supervision: ``blurry`` (recorded frames), ``multi-exposure`` (frames of several
            exposures, no events) or ``sharp-hdr`` (truth sharp HDR at true poses: the oracle).
    """

    description: str
    imaging: str = "pixel"
    crf: str = "mlp"
    events: EventModelSpec | None = field(default_factory=EventModelSpec)
    supervision: str = "blurry"


VARIANTS: dict[str, Variant] = {
    "full": Variant("See-NeRF: pixel-wise RGB CRF, event CRF with delay MLP and calibrated bins"),
    "no-events": Variant("See-NeRF without the event loss", events=None),
    "naive-events": Variant(
        "ideal event model: no delay compensation, raw integer counts",
        events=EventModelSpec(delay="none", order=0, calibrated=False),
    ),
    "evdeblur-ecrf": Variant(
        "Ev-DeblurNeRF eCRF: learned RGB mix for events, no delay, raw counts",
        events=EventModelSpec(colour="learned", delay="none", order=0, calibrated=False),
    ),
    "v2e-lowpass": Variant(
        "explicit v2e second-order low-pass with the fixed intensity factor",
        events=EventModelSpec(delay="v2e", order=2),
    ),
    "deblur-e-lowpass": Variant(
        "explicit Deblur-e fourth-order low-pass with the fixed intensity factor",
        events=EventModelSpec(delay="v2e", order=4),
    ),
    "power-crf": Variant("EvHDR-GS power-function CRF x^a for all channels", crf="power"),
    "point-crf-3d": Variant("HDR-NeRF style CRF on 3-D samples, blur in LDR", imaging="point"),
    "base": Variant(
        "naive LDR field: no CRF, no events", imaging="ldr-field", crf="none", events=None
    ),
    "multi-exposure": Variant(
        "HDR-NeRF reference setting: frames at several exposures, no events",
        events=None,
        supervision="multi-exposure",
    ),
    "oracle": Variant(
        "upper bound: the same field trained on truth sharp linear HDR at true poses, "
        "LDR views through the true response",
        crf="true",
        events=None,
        supervision="sharp-hdr",
    ),
}
"""Every variant by name; ``full`` is the paper's method."""

LOW_PASS_READINGS: dict[str, dict] = {
    "reference": {"order": 1, "domain": "log"},
    "paper": {"order": 2, "domain": "linear"},
}
"""How ``full``'s delay filter reads eq. 10: the reference code (first order on log radiance)
or the paper's text (second order on linear radiance, ln afterwards)."""


def get_variant(name: str) -> Variant:
    """The variant called ``name``.

    Raises:
        ConfigError: unknown name (the message lists the known ones).
    """
    if name not in VARIANTS:
        raise ConfigError(f"unknown variant {name!r}; choose one of: {', '.join(VARIANTS)}")
    return VARIANTS[name]
