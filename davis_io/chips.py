"""DAVIS camera models: sensor size per model, chip names (AEDAT headers), default frame timing."""

from __future__ import annotations

import re

__all__ = [
    "COLOUR_MODELS",
    "DEFAULT_FRAME_GAP_US",
    "DEFAULT_MODEL",
    "SENSOR_SIZES",
    "identify_chip",
]

DEFAULT_FRAME_GAP_US = 50_000
"""Time from one frame's exposure start to the next one's beyond the exposure, by default (a
camera and the emulator alike): room for the readout, so no exposure overlaps the next."""

SENSOR_SIZES = {"DAVIS346": (346, 260), "DAVIS240": (240, 180)}
"""Camera model -> (width, height) in pixels of its DVS and APS arrays."""

DEFAULT_MODEL = "DAVIS346"
"""The model the emulator films with unless told another."""

COLOUR_MODELS = frozenset({"DAVIS346"})
"""Models also made with a colour filter (RGGB); the DAVIS240 was made mono only."""

_MODEL = re.compile(r"davis\s*(346|240)", re.IGNORECASE)


def identify_chip(name: str) -> tuple[str, int, int]:
    """Return ``(model, width, height)`` for a chip name; ``(name, 0, 0)`` if unknown.

    Accepts cAER names (``DAVIS346``, ``DAVIS346BSI``, ``DAVIS240C``) and jAER class names
    (``eu.seebetter.ini.chips.davis.Davis346BColor``, ``...DAVIS240C``).
    """
    match = _MODEL.search(name)
    if match is None:
        return name.strip(), 0, 0
    model = f"DAVIS{match.group(1)}"
    return (model, *SENSOR_SIZES[model])
