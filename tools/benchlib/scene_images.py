"""Side-by-side views of each scene: truth, ``full``, ``oracle`` and ``full``'s error map.

Each strip is the first held-out view of a session, as it is scored: every render multiplied by
its run's global HDR scale (``metrics.json``), then the open HDR protocol's tone map relative to
the truth's peak; the error map is the absolute difference of the tone-mapped ``full`` and
truth, magnified 4x. Written beside the report as ``scenes/SESSION.png``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenEXR

from benchlib.fits import run_name
from benchlib.plan import METHOD, UPPER_BOUND, Ladder
from davis_io.session import load_truth

__all__ = ["ERROR_GAIN", "IMAGES_FOLDER", "read_exr", "scene_strip", "write_scene_images"]

IMAGES_FOLDER = "scenes"
ERROR_GAIN = 4.0
"""The error map shows ``|full - truth|`` of the tone-mapped views times this."""

_GAP_PX = 4


def read_exr(path: Path) -> np.ndarray:
    """``(H, W, C)`` float32 of an OpenEXR written by ``seecap`` (RGB, or Y for monochrome)."""
    with OpenEXR.File(str(path)) as exr:
        channels = exr.channels()
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, np.float32)
        return np.asarray(channels["Y"].pixels, np.float32)[..., None]


def scene_strip(
    truth: np.ndarray, full: np.ndarray, oracle: np.ndarray | None, error_gain: float = ERROR_GAIN
) -> np.ndarray:
    """Truth, ``full``, ``oracle`` (grey when missing) and the error map, left to right.

    Args:
        truth: ``(H, W, C)`` linear HDR.
        full: ``full``'s render, already multiplied by its global scale.
        oracle: ``oracle``'s render likewise, or None.
        error_gain: magnification of the error map.

    Returns:
        ``(H, 4 W + 3 gap, C)`` in [0, 1], white gaps between the panels.
    """
    # seenerf imports torch; the report reads this module's constants without it.
    from seenerf.eval.metrics import tone_map_pair

    full_tone, truth_tone = tone_map_pair(full, truth)
    oracle_tone = (
        tone_map_pair(oracle, truth)[0] if oracle is not None else np.full_like(truth_tone, 0.5)
    )
    error = np.clip(np.abs(full_tone - truth_tone) * error_gain, 0.0, 1.0)
    gap = np.ones((truth.shape[0], _GAP_PX, truth.shape[2]), np.float32)
    panels = [np.clip(truth_tone, 0.0, 1.0), full_tone, oracle_tone, error]
    strip = [panels[0]]
    for panel in panels[1:]:
        strip += [gap, panel]
    return np.concatenate(strip, axis=1).astype(np.float32)


def _scaled_render(session: Path, variant: str, preset: str) -> np.ndarray | None:
    """The first held-out render of a run times its global HDR scale, or None if not there."""
    run = session / "fit" / run_name(Ladder(session.name, preset, variant, ()))
    view, metrics = run / "renders" / "hdr" / "000.exr", run / "metrics.json"
    if not (view.exists() and metrics.exists()):
        return None
    scale = np.asarray(json.loads(metrics.read_text())["hdr"]["scale"], np.float32)
    return read_exr(view) * scale


def write_scene_images(sessions: dict[str, Path], preset: str, out: Path) -> list[str]:
    """Write ``out/scenes/KEY.png`` for each (emulated) session whose ``full`` render exists.

    Returns:
        The sessions written, in the given order.
    """
    from seenerf.eval.export import write_png

    written = []
    for key, folder in sessions.items():
        full = _scaled_render(folder, METHOD, preset)
        if full is None:
            continue
        truth = load_truth(folder)
        oracle = _scaled_render(folder, UPPER_BOUND, preset)
        write_png(out / IMAGES_FOLDER / f"{key}.png", scene_strip(truth.test_hdr[0], full, oracle))
        written.append(key)
    return written
