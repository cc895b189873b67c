"""What a calibration cannot measure it says, stores as assumed, and replaces by a prior."""

import dataclasses

import numpy as np
import pytest
from synthetic_recording import KnownSensor, synthetic_recording

from davis_io.calibration import calibrate_frames
from davis_io.calibration.estimate import (
    LATENCIES_US,
    LONGER_LATENCIES_US,
    CalibrationInput,
)
from davis_io.calibration.plausible import Assumptions, flat_profile
from davis_io.emulator import Response
from davis_io.emulator.aps import ApsSettings, expose
from davis_io.gaps import find_gaps

FILM = Response("film", midpoint=0.4, width=1.2)


@pytest.fixture(scope="module")
def recording():
    return synthetic_recording(KnownSensor(0.25, 0.35, 0.02, FILM))


def _cut(recording, after_frames, margin_us=3_000):
    """The recording without the events between the exposures after ``after_frames``."""
    keep = np.ones(len(recording.times_us), bool)
    for k in after_frames:
        start = recording.exposure_end_us[k] + margin_us
        end = recording.exposure_start_us[k + 1] - margin_us
        keep &= ~((recording.times_us > start) & (recording.times_us < end))
    return dataclasses.replace(
        recording,
        times_us=recording.times_us[keep],
        x=recording.x[keep],
        y=recording.y[keep],
        is_on=recording.is_on[keep],
    )


def test_a_recording_with_gaps_calibrates_without_pairing_across_them(recording):
    full, theta_on, theta_off = recording
    cut = _cut(full, after_frames=(1, 3, 5))  # 34 ms without events after frames 1, 3 and 5
    gaps = find_gaps(cut.times_us)
    assert len(gaps) == 3
    told = calibrate_frames(dataclasses.replace(cut, gaps_us=gaps))
    # Pairs (0, 1), (2, 3), (4, 5), (6, 7) only: the three across gaps are left out.
    assert told.pairs < 0.65 * calibrate_frames(full).pairs
    assert told.assumed == {}
    assert told.threshold_on == pytest.approx(np.median(theta_on), rel=0.03)
    assert told.threshold_off == pytest.approx(np.median(theta_off), rel=0.03)
    # Read across the gaps, the frames change by more than their events say: the blur can no
    # longer pin the thresholds' scale.
    blind = calibrate_frames(cut)
    assert "threshold_scale" in blind.assumed


def test_with_no_pair_left_only_the_levels_and_dead_time_are_measured(recording):
    full, _, _ = recording
    cut = _cut(full, after_frames=range(len(full.frames) - 1))
    calibration = calibrate_frames(dataclasses.replace(cut, gaps_us=find_gaps(cut.times_us)))
    assert calibration.source == "assumed"
    assert set(calibration.assumed) == {"thresholds", "latency_us", "pixel_factors", "response"}
    assert (calibration.threshold_on, calibration.threshold_off) == (0.3, 0.3)
    assert calibration.threshold_on_sd == 0.15 and not calibration.response_linear
    assert "gaps in the stream" in calibration.assumed["thresholds"]


@pytest.mark.parametrize(("response", "raw"), [("linear", True), ("film", False)])
def test_frames_whose_response_cannot_be_measured_are_raw_if_their_noise_never_falls(response, raw):
    # Noisy frames of a smooth scene and three events: nothing to link them, so the response
    # is assumed; the raw frames' shot noise grows with the level, the film curve's falls.
    settings = ApsSettings(Response(response), gain_per_s=1 / 0.15)
    rows, columns = np.mgrid[0:120, 0:160]
    radiance = np.exp(-7 + 8.5 * columns / 160) * (1 + 0.2 * np.sin(rows / 15))
    rng = np.random.default_rng(4)
    frames = np.stack([expose(radiance[None], 0.15, settings, rng, np.ones(1)) for _ in range(4)])
    starts = np.arange(4) * 200_000
    recording = CalibrationInput(
        frames=frames / 1023,
        adc_step=1 / 1023,
        times_us=np.array([10, 20, 30]),
        x=np.array([1, 2, 3], np.uint16),
        y=np.array([1, 1, 1], np.uint16),
        is_on=np.array([True, False, True]),
        exposure_start_us=starts,
        exposure_end_us=starts + 150_000,
    )
    calibration = calibrate_frames(recording)
    assert calibration.response_linear is raw and "response" in calibration.assumed
    assert ("as a raw DAVIS frame's" in calibration.assumed["response"]) is raw
    assert (calibration.noise_gain > 0) is raw  # a raw frame's noise is measured for the fit


def test_a_recording_with_almost_no_events_assumes_what_the_events_would_measure(recording):
    full, _, _ = recording
    sparse = dataclasses.replace(
        full,
        times_us=full.times_us[::2000],
        x=full.x[::2000],
        y=full.y[::2000],
        is_on=full.is_on[::2000],
    )
    calibration = calibrate_frames(sparse)
    assert calibration.source == "assumed"
    assert set(calibration.assumed) >= {"thresholds", "latency_us", "pixel_factors", "response"}
    assert (calibration.threshold_on, calibration.threshold_off) == (0.3, 0.3)
    events = len(sparse.times_us)
    assert f"too few events to measure from: {events}," in calibration.assumed["thresholds"]
    # The whole recording is well above the limit.
    assert "thresholds" not in calibrate_frames(full).assumed


def test_a_latency_beyond_the_first_profile_is_measured_on_its_longer_latencies(recording):
    full, _, _ = recording
    late = dataclasses.replace(full, times_us=full.times_us + 20_000)  # a slow pixel in the dark
    lines = []
    calibration = calibrate_frames(late, progress=lines.append)
    assert max(LATENCIES_US) == 12_000 and LONGER_LATENCIES_US[:2] == (16_000, 24_000)
    assert calibration.latency_us == pytest.approx(20_000, abs=1_000)
    assert "latency_us" not in calibration.assumed
    # The profile went on to 16 and 24 ms, where the best stopped being the last one tried.
    tried = {line.split(":")[0] for line in lines if line.startswith("latency ")}
    assert {"latency 16 ms", "latency 24 ms"} <= tried and "latency 32 ms" not in tried


def test_a_latency_at_the_end_of_its_profile_is_assumed_not_measured(recording):
    full, _, _ = recording
    late = dataclasses.replace(full, times_us=full.times_us + 45_000)  # beyond the 32 ms tried
    calibration = calibrate_frames(late)
    assert calibration.latency_us == 0
    assert "its last value, 32 ms" in calibration.assumed["latency_us"]
    assert max(LONGER_LATENCIES_US) == 32_000


def test_a_recording_at_usual_light_is_profiled_to_12_ms_only(recording):
    full, _, _ = recording
    lines = []
    calibrate_frames(full, progress=lines.append)
    tried = {line.split(":")[0] for line in lines if line.startswith("latency ")}
    assert "latency 12 ms" in tried and "latency 16 ms" not in tried


def test_a_response_straight_only_below_zero_is_not_called_linear():
    from davis_io.calibration.estimate import _reviewed_response
    from davis_io.calibration.response_fit import FrameLevels, InverseResponse

    # The curve of an unknown camera: ln g = 0.32 ln(v + 0.1), straight in ln(v - black) only
    # for black = -0.1, which no frame can have.
    knots = np.linspace(0.1, 0.9, 12)
    response = InverseResponse(knots, 0.32 * (np.log(knots + 0.1) - np.log(0.2)))
    found = type("Found", (), {"response": response})()
    notes = Assumptions(lambda line: None)
    levels = FrameLevels(black_level=0.0, saturation=1.0, low=0.06, high=0.98)
    black, saturation, linear = _reviewed_response(found, levels, notes, lambda line: None)
    assert not linear and black == 0.0 and saturation == 1.0
    assert "below any black level a frame can have" in notes.reasons["response"]


def test_linear_frames_whose_dark_end_noise_bends_the_curve_are_linear_with_black_at_zero():
    from davis_io.calibration.estimate import _reviewed_response
    from davis_io.calibration.response_fit import FrameLevels, InverseResponse

    # Linear frames with black at 0, the thresholds 0.8 of the nominal: ln g = 0.8 ln v, but
    # noise in the values under 0.1 halves the free curve's slope there. The straightest black
    # is then below zero, and above the dark end the curve is the line through 0.
    knots = np.geomspace(0.04, 0.98, 16)
    log_v = np.log(knots)
    log_g = 0.8 * np.where(knots >= 0.1, log_v, np.log(0.1) + 0.5 * (log_v - np.log(0.1)))
    found = type("Found", (), {"response": InverseResponse(knots, log_g - log_g[0])})()
    notes = Assumptions(lambda line: None)
    levels = FrameLevels(black_level=0.0, saturation=1.0, low=0.04, high=0.98)
    lines = []
    black, saturation, linear = _reviewed_response(found, levels, notes, lines.append)
    assert "+" in lines[0]  # the straightest black found: below zero
    assert black == 0.0 and saturation == 1.0 and "response" not in notes.reasons
    assert linear == pytest.approx(0.8, abs=0.005)  # the power above the dark end
    assert "power 0.80 of v to 0.000 RMS" in lines[1]

    # Frames that never leave the dark end give the line through 0 nothing to stand on.
    dark = knots * 0.09
    found = type("Found", (), {"response": InverseResponse(dark, log_g - log_g[0])})()
    notes = Assumptions(lambda line: None)
    levels = FrameLevels(black_level=0.0, saturation=1.0, low=dark[0], high=dark[-1])
    black, _, linear = _reviewed_response(found, levels, notes, lambda line: None)
    assert linear is None and black == 0.0 and "below any black level" in notes.reasons["response"]


def test_a_raw_frames_bent_curve_is_linear_but_not_without_the_raw_marks():
    from davis_io.calibration.estimate import _reviewed_response
    from davis_io.calibration.response_fit import FrameLevels, InverseResponse

    # The free curve measured on linear frames of an emulated dark scene: 0.041 RMS from a
    # straight line in ln(v - 0.0147).
    knots = np.array(
        [0.0753, 0.0792, 0.0841, 0.089, 0.0958, 0.1026, 0.1095, 0.1193, 0.13, 0.1437, 0.1593]
        + [0.1779, 0.1984, 0.2239, 0.2864, 0.6647]
    )
    log_g = np.array(
        [0.0, 0.0325, 0.1118, 0.1825, 0.2725, 0.3554, 0.4339, 0.5479, 0.6499, 0.7596, 0.8887]
        + [1.0105, 1.1341, 1.2629, 1.5709, 2.6967]
    )
    found = type("Found", (), {"response": InverseResponse(knots, log_g)})()
    # The frames pile up at 0.0147 and clip at 0.863: a raw ADC's marks.
    raw = FrameLevels(black_level=0.0147, saturation=0.863, low=0.075, high=0.84)
    lines = []
    black, saturation, linear = _reviewed_response(
        found, raw, Assumptions(lambda line: None), lines.append
    )
    assert lines == ["response linear: the free curve is a power 1.12 of v - 0.015 to 0.041 RMS"]
    assert (black, saturation) == (0.0147, 0.863) and linear == pytest.approx(1.117, abs=0.001)
    # The same curve from frames that never clip below full scale is held to the strict limit.
    unclipped = FrameLevels(black_level=0.0147, saturation=1.0, low=0.075, high=0.84)
    _, _, linear = _reviewed_response(found, unclipped, Assumptions(lambda line: None), print)
    assert linear is None


@pytest.mark.parametrize(
    ("measured", "held", "said"),
    [
        (True, None, None),  # the blur pins the scale
        (True, (0.25, 0.30), None),  # the linear frames state it better
        (False, (0.25, 0.30), "the linear frames' scale, with the measured ratio"),
        (False, None, "the nominal 0.3 with the measured ratio"),  # neither
    ],
)
def test_the_scale_is_the_linear_frames_else_the_blurs_else_nominal(measured, held, said):
    from davis_io.calibration.estimate import _HeldLine, _reviewed_scale

    scale = type("Scale", (), {"measured": measured})()
    found = type("Found", (), {"scale": scale, "pixel_share": np.array([0.02, 0.08])})()
    theta, spread = np.array([0.27, 0.33]), np.array([0.01, 0.01])
    notes = Assumptions(lambda line: None)
    line = None if held is None else _HeldLine(np.array(held), np.zeros(0), np.zeros(0))
    got, uncertainty = _reviewed_scale(found, (theta, spread), line, notes)
    if held is None:
        np.testing.assert_allclose(got, theta)
        np.testing.assert_allclose(uncertainty, spread)
    else:
        np.testing.assert_allclose(got, held)
        # The pixels' split-half share where it is larger, else 5 % of each threshold.
        np.testing.assert_allclose(uncertainty, [0.0125, 0.024])
    if said is None:
        assert "threshold_scale" not in notes
    else:
        assert said in notes.reasons["threshold_scale"]


def test_a_flat_profile_locates_nothing():
    assert flat_profile(np.array([0.4085, 0.4101, 0.4120]))  # under 1 % apart
    assert not flat_profile(np.array([0.66, 0.60, 0.59, 0.77]))
    assert flat_profile(np.array([np.inf, 0.5]))  # one finite value: nothing to compare


def test_an_estimate_off_the_physical_range_is_replaced_and_said(capsys):
    lines = []
    notes = Assumptions(lines.append)
    from davis_io.calibration.plausible import DEAD_TIME_US

    assert not notes.check("dead_time_us", 50_000, DEAD_TIME_US, "no dead time (0)")
    assert "dead_time_us" in notes
    assert lines == [
        "dead_time_us not measured (50000 is outside what a DAVIS can have (a whole number "
        "from 0 to 20000 µs)): no dead time (0)"
    ]


@pytest.mark.parametrize(
    ("black", "power", "said"),
    [
        (0.0, 1.05, "the frames no black level"),  # a black level found only by the search
        (0.02, 1.8, "power 1.80 is too far from 1"),  # a tone curve straight in ln v
    ],
)
def test_a_blur_pinned_scale_is_not_traded_for_a_doubtful_line(black, power, said):
    from davis_io.calibration.estimate import _held_linear
    from davis_io.calibration.response_fit import FrameLevels

    scale = type("Scale", (), {"measured": True})()
    found = type("Found", (), {"scale": scale})()  # no problem: it must not be fitted again
    levels = FrameLevels(black_level=black, saturation=0.9, low=black + 0.06, high=0.88)
    lines = []
    assert _held_linear(found, levels, 0.02, power, lines.append) is None
    assert said in lines[0]
