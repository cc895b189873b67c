"""Session folders: manifest, reader and truth format (the recorder: ``session.recorder``)."""

from davis_io.session.manifest import DropCounters, SessionManifest, read_manifest
from davis_io.session.records import FramesTable, SessionBins, SessionPoses
from davis_io.session.store import Session
from davis_io.session.truth import TRUTH_DIR, Truth, load_truth, save_truth

__all__ = [
    "TRUTH_DIR",
    "DropCounters",
    "FramesTable",
    "Session",
    "SessionBins",
    "SessionManifest",
    "SessionPoses",
    "Truth",
    "load_truth",
    "read_manifest",
    "save_truth",
]
