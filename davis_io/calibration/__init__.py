"""Sensor calibration measured from a recording: contrast thresholds, latency, levels, response."""

from davis_io.calibration.estimate import CalibrationInput, calibrate_frames

__all__ = ["CalibrationInput", "calibrate_frames"]
