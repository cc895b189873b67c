"""Session folders: manifest, reader and truth format (the recorder: ``session.recorder``).

Also re-exported here, as the contract a trainer reads sessions by: the colour filter and its
weights, the bins' sub-division and trapezoid weights, bins in light time, the shared defaults
and durations.
"""

from davis_io.bins import subdivide, trapezoid_weights
from davis_io.colorfilter import filter_weights
from davis_io.session.bounds import Bounds
from davis_io.session.calibration import SensorCalibration, default_calibration
from davis_io.session.defaults import DEFAULT_BINS, DEFAULT_THRESHOLD
from davis_io.session.light_bins import contrast_bins
from davis_io.session.lock import SessionBusy, writer_lock
from davis_io.session.manifest import DropCounters, SessionManifest, read_manifest
from davis_io.session.records import FramesTable, SessionBins, SessionPoses
from davis_io.session.store import Session
from davis_io.session.truth import TRUTH_DIR, Truth, load_truth, save_truth
from davis_io.session.units import parse_duration_us, seconds_argument
from davis_io.session.writer import not_written, output_errors
from davis_io.types import ColorFilter

__all__ = [
    "Bounds",
    "DEFAULT_BINS",
    "DEFAULT_THRESHOLD",
    "TRUTH_DIR",
    "ColorFilter",
    "DropCounters",
    "FramesTable",
    "Session",
    "SessionBins",
    "SessionManifest",
    "SessionPoses",
    "SensorCalibration",
    "SessionBusy",
    "Truth",
    "contrast_bins",
    "default_calibration",
    "filter_weights",
    "load_truth",
    "not_written",
    "output_errors",
    "parse_duration_us",
    "read_manifest",
    "save_truth",
    "seconds_argument",
    "subdivide",
    "trapezoid_weights",
    "writer_lock",
]
