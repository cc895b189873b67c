"""The training data a fit reads: the variant picks the sensor's source; a stated threshold wins."""

import pytest

from davis_io.session import Session
from davis_io.session.calibration import default_calibration
from davis_io.session.truth import load_truth
from seenerf.model.config import FitConfig
from seenerf.train.session_fit import training_data

BINS = 4
MEASURED = 0.31
"""The calibration stored in the session: neither the truth's mean threshold nor the stated one."""


@pytest.fixture
def calibrated(copies):
    (folder,) = copies("measured")
    with Session.open(folder) as session:
        session.write_calibration(default_calibration(MEASURED, "stated, for a test"))
    return folder


def test_a_recording_variant_reads_the_calibration_and_a_stated_threshold_replaces_it(calibrated):
    assert training_data(calibrated, BINS, FitConfig.of()).threshold == pytest.approx(MEASURED)
    stated = training_data(calibrated, BINS, FitConfig.of(threshold=0.22))
    assert stated.threshold == pytest.approx(0.22)


def test_the_white_box_variant_reads_the_emulated_sensors_truth(calibrated):
    true = load_truth(calibrated / "truth").sensor_calibration().threshold
    assert abs(true - MEASURED) > 0.005  # the two sources are told apart
    data = training_data(calibrated, BINS, FitConfig.of(variant="white-box"))
    assert data.threshold == pytest.approx(true)
    assert data.num_bins == BINS and data.num_frames == 4
