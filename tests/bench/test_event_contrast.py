import numpy as np
import pytest
from event_contrast import agreement, log_changes, sensor_values, settled_spans, with_true_parts

from davis_io.emulator import EmulatedCamera
from davis_io.session import SensorCalibration
from davis_io.session.recorder import record

SMALL = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=1, exposure_us=40_000)


def recorded(folder, preset):
    camera = EmulatedCamera("room", seed=1, dvs_preset=preset, **SMALL)
    record(camera, folder)
    camera.write_truth(folder)
    return folder


def test_events_of_ideal_pixels_carry_the_whole_log_change(tmp_path):
    folder = recorded(tmp_path / "s", "clean")
    (true,), implied, threshold = log_changes(folder, b=4, frames=2, threshold=None)
    # The clean preset's 0.2 with a spread of 0.02, read from the truth: the median pixel's,
    # within 3 standard errors (0.02 * 1.25 / sqrt(64 * 48)) of it.
    assert threshold == pytest.approx(0.2, abs=0.0015)
    moved = np.abs(true) > 2 * threshold
    assert moved.sum() > 100
    ratio = np.median(implied[moved] / true[moved])
    assert 0.9 < ratio < 1.1
    assert np.corrcoef(true[moved], implied[moved])[0, 1] > 0.9


def test_events_of_bandwidth_limited_pixels_undercount_the_log_change(tmp_path):
    folder = recorded(tmp_path / "s", "noisy")
    (true,), implied, threshold = log_changes(folder, b=4, frames=2, threshold=None)
    moved = np.abs(true) > 2 * threshold
    assert np.median(implied[moved] / true[moved]) < 0.9


def test_ideal_events_agree_best_at_no_latency_and_late_events_a_few_ms_later(tmp_path):
    def correlations(preset):
        folder = recorded(tmp_path / preset, preset)
        true, implied, threshold = log_changes(folder, 4, 2, None, (0, 4_000))
        return [agreement(changes, implied, threshold)["correlation"] for changes in true]

    # Ideal pixels fire within the 2 ms DVS step of the change: any latency assumed hurts.
    on_time, late = correlations("clean")
    assert on_time > late
    # The noisy preset's pixels (500 µs refractory, one-step delay, low-pass) fire late.
    on_time, late = correlations("noisy")
    assert late > on_time


def test_agreement_of_a_known_pair():
    true = np.array([1.0, -1.0, 2.0, 0.1])
    found = agreement(true, 0.5 * true, 0.3)
    assert found["pixels"] == 3  # 0.1 is under the threshold
    assert np.isclose(found["ratio"], 0.5) and np.isclose(found["slope"], 0.5)
    assert np.isclose(found["correlation"], 1.0)


def test_rises_and_falls_get_slopes_of_their_own():
    true = np.array([1.0, -2.0, 3.0, -1.0])
    found = agreement(true, np.where(true > 0, 0.8 * true, 1.2 * true), 0.3)
    assert found["slope_rise"] == pytest.approx(0.8)
    assert found["slope_fall"] == pytest.approx(1.2)
    # sum(implied * true) = 0.8 + 4.8 + 7.2 + 1.2 = 14 over sum(true^2) = 15.
    assert found["slope"] == pytest.approx(14 / 15)


def test_bins_read_as_a_fit_reads_them_carry_an_ideal_pixels_contrast(tmp_path):
    def slope(preset):
        folder = recorded(tmp_path / preset, preset)
        true, implied, threshold = log_changes(
            folder, 4, 2, None, calibration=sensor_values(folder, "truth")
        )
        return agreement(true[0], implied, threshold)["slope"]

    # In light time, each event its pixel's true threshold: only quantisation is lost.
    clean = slope("clean")
    assert 0.88 < clean < 1.05
    # The noisy preset's refractory period and low-pass lose a third, whatever the calibration.
    assert slope("noisy") < clean - 0.15


def test_spans_run_between_settled_points():
    # Two pixels, b = 3. Pixel 0 settled everywhere: its three bins are three spans. Pixel 1
    # not settled at points 1 and 2: one span from point 0 to 3, its bins summed.
    seen = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 5.0], [6.0, 9.0]])
    counted = np.array([[0.5, 1.0], [1.0, 1.0], [1.5, 4.0]])
    settled = np.array([[True, True], [True, False], [True, False], [True, True]])
    true, implied = settled_spans(seen, counted, settled)
    assert sorted(zip(true.tolist(), implied.tolist(), strict=True)) == [
        (1.0, 0.5),
        (2.0, 1.0),
        (3.0, 1.5),
        (9.0, 6.0),
    ]
    # Unsettled at the first point: pixel 1's span starts where it settles (point 3), no span.
    settled[0, 1] = False
    true, _ = settled_spans(seen, counted, settled)
    assert sorted(true.tolist()) == [1.0, 2.0, 3.0]


def test_parts_of_a_calibration_come_from_the_truth():
    measured = SensorCalibration(0.3, 0.2, latency_us=9000, pixel_factor_on=np.full((2, 2), 0.9))
    truth = SensorCalibration(0.4, 0.25, latency_us=3000, pixel_factor_on=np.full((2, 2), 1.1))
    mixed = with_true_parts(measured, truth, ("latency", "factors"))
    assert (mixed.threshold_on, mixed.threshold_off, mixed.latency_us) == (0.3, 0.2, 3000)
    assert mixed.pixel_factor_on.tolist() == [[1.1, 1.1], [1.1, 1.1]]
    mixed = with_true_parts(measured, truth, ("thresholds",))
    assert (mixed.threshold_on, mixed.threshold_off, mixed.latency_us) == (0.4, 0.25, 9000)
    with pytest.raises(ValueError, match="unknown calibration parts"):
        with_true_parts(measured, truth, ("gain",))


def test_bins_over_settled_spans_of_ideal_pixels_carry_their_contrast(tmp_path):
    folder = recorded(tmp_path / "clean", "clean")
    true, implied, threshold = log_changes(
        folder, 4, 2, None, calibration=sensor_values(folder, "truth"), spans=True
    )
    assert 0.88 < agreement(true[0], implied, threshold)["slope"] < 1.05
