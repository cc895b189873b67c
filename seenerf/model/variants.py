"""The paper's method and its comparisons as named variants: one table, no if/else on names."""

from __future__ import annotations

from dataclasses import dataclass, field

from torch import nn

from seenerf.model.imaging import LDR_FIELD, PIXEL, POINT, Imaging
from seenerf.sensors.event_crf import EventModelSpec
from seenerf.sensors.rgb_crf import PowerCrf, RgbCrf, TabulatedCrf

__all__ = [
    "LOW_PASS_READINGS",
    "VARIANTS",
    "Variant",
]


@dataclass(frozen=True)
class Variant:
    """What is supervised and how the sensors are modelled.

    Attributes:
        description: one line for ``--help`` and reports.
        imaging: how rendered values become pixels (:mod:`seenerf.model.imaging`):
            :data:`~seenerf.model.imaging.PIXEL` (blur in linear HDR, then the RGB CRF per
            pixel: the paper), :data:`~seenerf.model.imaging.POINT` (CRF on every 3-D sample,
            blur in LDR: HDR-NeRF style) or :data:`~seenerf.model.imaging.LDR_FIELD` (the field
            renders LDR directly, blur in LDR, no CRF).
        crf: the RGB response class: ``RgbCrf`` (three per-channel MLPs), ``PowerCrf`` (x^a),
            ``TabulatedCrf`` (the truth's table, the oracle) or None.
        events: the event model, or None for no event loss.
        method: the name of the method that trains it (:data:`seenerf.train.methods.METHODS`):
            ``recording`` (the recorded blurry frames and events at the estimated poses) or
            ``sharp-truth`` (the truth's sharp HDR at the true poses: the oracle).
        several_exposures: the recorded frames must have at least two exposures.
        sensor_from_truth: the sensor's values (thresholds of every pixel, event latency,
            cut-off, dead time, linear frames' noise) come from the emulator's truth instead of
            the session's calibration.
    """

    description: str
    imaging: Imaging = PIXEL
    crf: type[nn.Module] | None = RgbCrf
    events: EventModelSpec | None = field(default_factory=EventModelSpec)
    method: str = "recording"
    several_exposures: bool = False
    sensor_from_truth: bool = False


VARIANTS: dict[str, Variant] = {
    "full": Variant("See-NeRF: pixel-wise RGB CRF, event CRF with delay MLP and calibrated bins"),
    "white-box": Variant(
        "See-NeRF given the emulated sensor's true values instead of measured ones: every "
        "pixel's thresholds, the event latency, the cut-off, the dead time, linear frames' noise",
        sensor_from_truth=True,
    ),
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
    "power-crf": Variant("EvHDR-GS power-function CRF x^a for all channels", crf=PowerCrf),
    "point-crf-3d": Variant("HDR-NeRF style CRF on 3-D samples, blur in LDR", imaging=POINT),
    "base": Variant("naive LDR field: no CRF, no events", imaging=LDR_FIELD, crf=None, events=None),
    "multi-exposure": Variant(
        "HDR-NeRF reference setting: frames at several exposures, no events",
        events=None,
        several_exposures=True,
    ),
    "oracle": Variant(
        "upper bound: the same field trained on truth sharp linear HDR at true poses, "
        "LDR views through the true response",
        crf=TabulatedCrf,
        events=None,
        method="sharp-truth",
    ),
}
"""Every variant by name; ``full`` is the paper's method."""

LOW_PASS_READINGS: dict[str, dict] = {
    "reference": {"order": 1, "domain": "log"},
    "paper": {"order": 2, "domain": "linear"},
}
"""How ``full``'s delay filter reads eq. 10: the reference code (first order on log radiance)
or the paper's text (second order on linear radiance, ln afterwards)."""
