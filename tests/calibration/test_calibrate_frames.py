"""The calibration recovers known sensors from recordings made with exactly known values."""

import dataclasses

import numpy as np
import pytest
from synthetic_recording import KnownSensor, synthetic_recording

from davis_io.calibration import calibrate_frames
from davis_io.emulator import Response

FAMILIES = {
    "linear": Response("linear", black=0.04, slope=0.3, saturation=0.95),
    "reinhard_gamma": Response("reinhard_gamma", gain=1.3, gamma=2.4),
    "film": Response("film", midpoint=0.4, width=1.2),
    "s_curve": Response("s_curve", contrast=1.6),
}


@pytest.fixture(scope="module")
def calibrated():
    found = {}
    for name, response in FAMILIES.items():
        recording, theta_on, theta_off = synthetic_recording(
            KnownSensor(0.25, 0.35, 0.02, response)
        )
        found[name] = (calibrate_frames(recording), np.median(theta_on), np.median(theta_off))
    return found


@pytest.mark.parametrize("family", FAMILIES)
def test_thresholds_of_each_polarity_are_recovered_whatever_the_response(calibrated, family):
    calibration, true_on, true_off = calibrated[family]
    # Measured on these recordings: within 0.5 % (4 to 5 % high with the light read flat at
    # the last level, a staircase under a ramp).
    assert calibration.threshold_on == pytest.approx(true_on, rel=0.03)
    assert calibration.threshold_off == pytest.approx(true_off, rel=0.03)
    # The polarities differ by 40 %; their ratio is measured far tighter than either.
    ratio = calibration.threshold_off / calibration.threshold_on
    assert ratio == pytest.approx(true_off / true_on, rel=0.03)
    assert 0 < calibration.threshold_on_sd < 0.02 and calibration.source == "measured"
    assert calibration.assumed == {}  # every value measured


def test_the_linear_response_is_told_apart_and_its_levels_found(calibrated):
    assert [name for name, (c, _, _) in calibrated.items() if c.response_linear] == ["linear"]
    linear = calibrated["linear"][0]
    # This scene never goes black: the black level is where the linear curve meets no light.
    assert linear.black_level == pytest.approx(0.04, abs=0.01)
    assert linear.saturation == pytest.approx(0.95, abs=2 / 1023)  # frames clip there
    film = calibrated["film"][0]
    assert film.black_level == 0.0 and film.saturation == 1.0  # no pile-up: not claimed
    # The noise is measured on linear frames alone (elsewhere it is no line in the value).
    assert linear.noise_floor > 0 and "frame noise" in linear.method
    assert all(
        c.noise_gain == c.noise_floor == 0 for c, _, _ in calibrated.values() if c is not linear
    )


def test_the_inverse_response_rises_and_matches_the_true_shape(calibrated):
    calibration, _, _ = calibrated["reinhard_gamma"]
    values, log_g = calibration.response_value, calibration.response_log_exposure
    assert np.all(np.diff(values) > 0) and np.all(np.diff(log_g) > 0)
    response = FAMILIES["reinhard_gamma"]
    x = np.exp(np.linspace(-6, 4, 4001))
    true_log_g = np.interp(values, response(x), np.log(x))
    # Up to the constant ln g carries, the measured curve follows the true one within 8 %.
    span = true_log_g[-1] - true_log_g[0]
    departure = (log_g - log_g[0]) - (true_log_g - true_log_g[0])
    assert np.max(np.abs(departure)) < 0.08 * span


def test_pixels_far_below_the_median_threshold_do_not_drag_the_thresholds_down():
    # OFF thresholds of 0.16 spread by 0.06: some pixels fire at a quarter of the median
    # threshold or less, and each of their pairs counts four times the events.
    sensor = KnownSensor(0.45, 0.16, 0.06, FAMILIES["film"])
    recording, theta_on, theta_off = synthetic_recording(sensor, seed=3)
    assert np.mean(theta_off < 0.3 * np.median(theta_off)) > 0.005
    calibration = calibrate_frames(recording)
    assert calibration.threshold_on == pytest.approx(np.median(theta_on), rel=0.08)
    assert calibration.threshold_off == pytest.approx(np.median(theta_off), rel=0.08)
    assert calibration.residual_events < 1.0


def test_late_events_are_measured_as_late():
    recording, _, _ = synthetic_recording(KnownSensor(0.25, 0.35, 0.02, FAMILIES["film"]))
    late = dataclasses.replace(recording, times_us=recording.times_us + 5000)
    on_time, delayed = calibrate_frames(recording), calibrate_frames(late)
    assert delayed.latency_us - on_time.latency_us == pytest.approx(5000, abs=1000)
    assert delayed.threshold_on == pytest.approx(on_time.threshold_on, rel=0.03)


def test_the_latency_is_profiled_again_once_the_thresholds_have_settled():
    # Very different polarities with a wide spread: the first thresholds (no latency, no pixel
    # factors) are far off, and the disagreement profiled there hardly moves with the latency.
    # Profiled once, 3 ms of added latency was measured as 2.2 ms and the thresholds 7 % high.
    sensor = KnownSensor(0.45, 0.16, 0.06, FAMILIES["film"])
    recording, theta_on, theta_off = synthetic_recording(sensor, seed=4)
    late = dataclasses.replace(recording, times_us=recording.times_us + 3000)
    on_time, delayed = calibrate_frames(recording), calibrate_frames(late)
    # Read flat at the last level (a staircase), these ideal pixels' light looked 2.7 ms late.
    assert on_time.latency_us <= 500
    assert delayed.latency_us == pytest.approx(3000, abs=500)
    assert delayed.threshold_on == pytest.approx(np.median(theta_on), rel=0.03)
    assert delayed.threshold_off == pytest.approx(np.median(theta_off), rel=0.03)


def test_frames_too_sharp_for_the_scale_keep_the_measured_ratio_at_the_nominal_scale():
    # A 4 ms exposure barely blurs: the free response absorbs any common scale of the
    # thresholds (unguarded, the fit ran to its floor of 0.01). The ratio stays measurable.
    sensor = KnownSensor(0.25, 0.35, 0.02, FAMILIES["film"])
    recording, theta_on, theta_off = synthetic_recording(sensor, exposure_us=4_000)
    calibration = calibrate_frames(recording)
    assert calibration.source == "measured ratio, nominal scale"
    assert np.sqrt(calibration.threshold_on * calibration.threshold_off) == pytest.approx(0.3)
    ratio = calibration.threshold_off / calibration.threshold_on
    assert ratio == pytest.approx(np.median(theta_off) / np.median(theta_on), rel=0.03)
    # The profile is flat over a factor of two or more: the stated uncertainty says so.
    assert calibration.threshold_on_sd > 0.4 * calibration.threshold_on


@pytest.mark.parametrize(
    ("on", "off", "slope"), [(0.15, 0.21, 0.6), (0.45, 0.35, 0.6), (0.25, 0.35, 0.3)]
)
def test_linear_frames_too_sharp_for_the_blur_state_the_scale_themselves(on, off, slope):
    # The same 4 ms exposures, frames linear above a black level: held to ln(v - black), the
    # frames' changes are the events' own, at the true thresholds' scale. Read instead as the
    # nominal scale times the power the free curve solved at it has (the power is the nominal
    # over the true scale), they came out 2.9 and 0.56 times the truth. At a slope of 0.3 the
    # darkest texture's values, 0.013 above black, looked like its pile-up (0.07 % of them);
    # held to that line the thresholds were 9 % high.
    response = Response("linear", black=0.04, slope=slope, saturation=0.95)
    recording, theta_on, theta_off = synthetic_recording(
        KnownSensor(on, off, 0.02, response), exposure_us=4_000
    )
    calibration = calibrate_frames(recording)
    assert calibration.source == "measured ratio, linear frames scale"
    assert calibration.threshold_on == pytest.approx(np.median(theta_on), rel=0.03)
    assert calibration.threshold_off == pytest.approx(np.median(theta_off), rel=0.03)
    assert calibration.threshold_on_sd >= 0.05 * calibration.threshold_on
    # The stored curve is the line the thresholds were fitted beside.
    values, log_g = calibration.response_value, calibration.response_log_exposure
    expected = np.log(values - calibration.black_level)
    np.testing.assert_allclose(log_g, expected - expected[0], atol=1e-9)


def test_linear_frames_that_never_go_black_keep_the_scale_the_blur_pins():
    # No pile-up tells the black level; the one that straightens the free curve best, 0.020
    # (true 0.040), would have put the thresholds held to its line 4.6 % low.
    response = Response("linear", black=0.04, slope=0.6, saturation=0.95)
    recording, theta_on, theta_off = synthetic_recording(KnownSensor(0.25, 0.35, 0.02, response))
    calibration = calibrate_frames(recording)
    assert calibration.response_linear and calibration.source == "measured"
    assert "held to ln(v - black)" not in calibration.method
    assert calibration.threshold_on == pytest.approx(np.median(theta_on), rel=0.02)
    assert calibration.threshold_off == pytest.approx(np.median(theta_off), rel=0.02)


@pytest.mark.parametrize("family", ["linear", "reinhard_gamma"])
def test_an_auto_exposure_that_changes_every_frame_is_measured_as_a_fixed_one(family):
    # 60, 30 and 15 ms in turn at one gain: consecutive frames of the same light differ by
    # ln 2 or ln 4, which the events do not see and the exposures' lengths explain.
    recording, theta_on, theta_off = synthetic_recording(
        KnownSensor(0.25, 0.35, 0.02, FAMILIES[family]), exposure_steps=(1.0, 0.5, 0.25)
    )
    calibration = calibrate_frames(recording)
    assert calibration.threshold_on == pytest.approx(np.median(theta_on), rel=0.03)
    assert calibration.threshold_off == pytest.approx(np.median(theta_off), rel=0.03)
    assert calibration.response_linear is (family == "linear")
    assert calibration.assumed == {}
