"""Emulated sessions with truth for the pose tests and what a calibration of the camera gives."""

from davis_io.emulator import EmulatedCamera
from davis_io.lens import Lens
from davis_io.session.recorder import record
from davis_io.session.truth import save_truth

REDUCED = {"frames": 8, "test_views": 2, "baseline_m": 0.18}
"""The default run's emulated session: 8 views at 346 x 260 on a 4 x 2 grid of capture
positions spread like the 16-view benchmark's 4 x 4 grid (the slow test runs that one)."""


def calibrated_lens(camera: EmulatedCamera) -> Lens:
    """A calibration of the emulated camera: its lens as a calibration file would state it."""
    return camera.config.optics


def record_emulated(folder, **settings):
    camera = EmulatedCamera(**settings)
    record(camera, folder, bins=4)
    save_truth(camera.truth, folder / "truth")
    return folder, calibrated_lens(camera)
