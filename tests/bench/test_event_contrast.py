import numpy as np
from event_contrast import log_changes

from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record

SMALL = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=1, exposure_us=40_000)


def test_events_of_ideal_pixels_carry_the_whole_log_change(tmp_path):
    session = record(EmulatedCamera("room", seed=1, dvs_preset="clean", **SMALL), tmp_path / "s")
    true, implied, threshold = log_changes(session.folder, b=4, frames=2, threshold=None)
    assert threshold == 0.2  # the clean preset's nominal threshold, read from session.json
    moved = np.abs(true) > 2 * threshold
    assert moved.sum() > 100
    ratio = np.median(implied[moved] / true[moved])
    assert 0.9 < ratio < 1.1
    assert np.corrcoef(true[moved], implied[moved])[0, 1] > 0.9


def test_events_of_bandwidth_limited_pixels_undercount_the_log_change(tmp_path):
    session = record(EmulatedCamera("room", seed=1, dvs_preset="noisy", **SMALL), tmp_path / "s")
    true, implied, threshold = log_changes(session.folder, b=4, frames=2, threshold=None)
    moved = np.abs(true) > 2 * threshold
    assert np.median(implied[moved] / true[moved]) < 0.9  # 0.76 when written
