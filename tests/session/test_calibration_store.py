"""The sensor calibration is stored in ``/calibration`` and read back whole."""

import dataclasses
import json

import h5py
import numpy as np
import pytest

from davis_io.errors import SessionError
from davis_io.session import SensorCalibration
from davis_io.session.calibration import read_calibration, write_calibration

MEASURED = SensorCalibration(
    threshold_on=0.376,
    threshold_off=0.261,
    threshold_on_sd=0.004,
    latency_us=7300,
    black_level=0.067,
    saturation=0.906,
    response_linear=True,
    dead_time_us=1982,
    noise_gain=1.5e-4,
    noise_floor=4.5e-7,
    response_value=np.array([0.1, 0.5, 0.9]),
    response_log_exposure=np.array([-2.0, 0.0, 1.5]),
    pixel_factor_on=np.full((2, 3), 1.1, np.float32),
    pixel_factor_off=np.full((2, 3), 0.9, np.float32),
    residual_events=1.01,
    pairs=111051,
    method="by hand",
)


def test_a_calibration_reads_back_as_written(tmp_path):
    with h5py.File(tmp_path / "session.h5", "w") as h5:
        write_calibration(h5, MEASURED)
        write_calibration(h5, MEASURED)  # replacing one is allowed
    with h5py.File(tmp_path / "session.h5", "r") as h5:
        read = read_calibration(h5)
    assert read.facts() == MEASURED.facts()
    for name in ("response_value", "response_log_exposure", "pixel_factor_on"):
        np.testing.assert_array_equal(getattr(read, name), getattr(MEASURED, name))


def test_a_calibration_older_than_the_dead_time_and_frame_noise_reads_them_unknown(tmp_path):
    with h5py.File(tmp_path / "session.h5", "w") as h5:
        write_calibration(h5, MEASURED)
        facts = json.loads(h5["/calibration"].attrs["facts"])
        del facts["dead_time_us"], facts["noise_gain"], facts["noise_floor"]
        h5["/calibration"].attrs["facts"] = json.dumps(facts)
        read = read_calibration(h5)
        assert read.dead_time_us == 0 and read.noise_gain == read.noise_floor == 0


def test_an_unreadable_calibration_names_the_command_that_measures_it_again(tmp_path):
    with h5py.File(tmp_path / "session.h5", "w") as h5:
        write_calibration(h5, MEASURED)
        h5["/calibration"].attrs["facts"] = json.dumps({"threshold_on": 0.3, "colour": "red"})
        with pytest.raises(SessionError, match="seecap calibrate SESSION --force"):
            read_calibration(h5)


def test_the_summary_states_the_dead_time_as_a_rate_only_when_measured():
    # 1982 µs: 1.98 ms, 1e6 / 1982 = 504.5 -> 505 events per second.
    assert "pixel dead time 1.98 ms (at most 505 events per second" in MEASURED.summary()
    assert "dead time" not in SensorCalibration(0.3, 0.3).summary()


def test_the_summary_states_the_frame_noise_only_when_measured():
    # 4.5e-7 / 1.5e-4 = 0.0030 above black: shot noise as large as read noise there.
    assert "read noise 0.0030 above black" in MEASURED.summary()
    assert "frame noise" not in SensorCalibration(0.3, 0.3).summary()


def test_a_stated_threshold_replaces_the_assumed_thresholds_and_nothing_else():
    assumed = {
        "thresholds": "at the search's bound",
        "pixel_factors": "never moved",
        "latency_us": "flat profile",
    }
    calibration = dataclasses.replace(MEASURED, assumed=assumed)
    assert not calibration.thresholds_measured
    stated = calibration.with_threshold(0.25)
    assert stated.thresholds_measured
    assert stated.assumed == {"latency_us": "flat profile"}
    assert (stated.threshold_on, stated.threshold_off, stated.source) == (0.25, 0.25, "given")
