"""Session folders: the manifest and the reader (the recorder is ``davis_io.session.recorder``)."""

from davis_io.session.manifest import DropCounters, SessionManifest, read_manifest
from davis_io.session.records import FramesTable, SessionBins, SessionPoses
from davis_io.session.store import Session

__all__ = [
    "DropCounters",
    "FramesTable",
    "Session",
    "SessionBins",
    "SessionManifest",
    "SessionPoses",
    "read_manifest",
]
