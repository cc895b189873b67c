"""The session manifest ``session.json``: what was recorded, from what, how, and how it ended."""

from __future__ import annotations

import dataclasses
import enum
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from davis_io import __version__
from davis_io.errors import SessionError, UsageError
from davis_io.lens import Lens
from davis_io.session.bounds import Bounds
from davis_io.session.defaults import BINS
from davis_io.types import ColorFilter, SourceInfo

__all__ = [
    "FORMAT_VERSION",
    "MANIFEST_NAME",
    "STATUS_COMPLETE",
    "STATUS_INTERRUPTED",
    "STATUS_RECORDING",
    "DropCounters",
    "SessionManifest",
    "read_manifest",
    "write_manifest",
]

FORMAT_VERSION = 1
MANIFEST_NAME = "session.json"
STATUS_RECORDING = "recording"
STATUS_COMPLETE = "complete"
STATUS_INTERRUPTED = "interrupted"
_STATUSES = (STATUS_RECORDING, STATUS_COMPLETE, STATUS_INTERRUPTED)


@dataclass
class DropCounters:
    """What was lost while recording; every counter is zero in a clean recording.

    Attributes:
        source_events: events the source reported lost (device FIFO, USB transfers).
        queue_packets: packets dropped because the writer queue was full.
        queue_events: events inside those dropped packets.
        queue_frames: frames inside those dropped packets.
        frames_events_lost: stored frames whose exposure window lost events.
    """

    source_events: int = 0
    queue_packets: int = 0
    queue_events: int = 0
    queue_frames: int = 0
    frames_events_lost: int = 0

    @property
    def total_events(self) -> int:
        """Events known lost from any cause."""
        return self.source_events + self.queue_events


@dataclass
class SessionManifest:
    """Contents of ``session.json`` (format version 1); times are µs unless named otherwise.

    Attributes:
        camera: camera model, e.g. ``"DAVIS346"``.
        serial: camera serial number ("" when unknown).
        width: sensor width in pixels.
        height: sensor height in pixels.
        color_filter: colour filter pattern (a :class:`ColorFilter` value, ``"mono"``).
        source: ``"usb"``, ``"replay:<file>"`` or ``"emulator:<scene>"``.
        b: number of event bins computed at record time.
        firmware_version: USB firmware version, when known.
        logic_version: FPGA logic version, when known.
        device_config: device configuration and biases as reported by the source.
        exposure_requested_us: exposure asked for on the command line (None: not set).
        exposure_measured_us: median exposure of the recorded frames (None: no frame).
        exposure_assumed_us: median exposure given to frames whose source stated none
            (:mod:`davis_io.session.unstated_exposure`); None: every frame stated its own.
        start_time_utc: ISO 8601 UTC wall-clock time the recording started.
        stop_time_utc: ISO 8601 UTC wall-clock time it stopped ("" while recording).
        status: ``"recording"``, ``"complete"`` or ``"interrupted"``.
        stop_reason: why an interrupted recording stopped ("" when complete).
        source_notes: what the source reported skipping or losing (a truncated file, unread
            streams, dropped frames), in its own words with byte offsets.
        frame_count: frames stored.
        event_count: events stored.
        drops: loss counters.
        event_gaps_us: ``[start, end]`` of every gap in the event stream, µs: no event
            anywhere for far longer than its rate allows (:mod:`davis_io.gaps`); None when the
            recorder did not look (older sessions: found from the events when read).
        lens: the camera's lens as its calibration file stated it at recording time
            (:meth:`davis_io.lens.Lens.to_json`), or None when none was given.
        format_version: session format version (1).
        tool_version: seecap version that wrote the session.
    """

    camera: str
    serial: str
    width: int
    height: int
    color_filter: str
    source: str
    b: int
    firmware_version: int | None = None
    logic_version: int | None = None
    device_config: dict = field(default_factory=dict)
    exposure_requested_us: int | None = None
    exposure_measured_us: int | None = None
    exposure_assumed_us: int | None = None
    start_time_utc: str = ""
    stop_time_utc: str = ""
    status: str = STATUS_RECORDING
    stop_reason: str = ""
    source_notes: list[str] = field(default_factory=list)
    frame_count: int = 0
    event_count: int = 0
    drops: DropCounters = field(default_factory=DropCounters)
    event_gaps_us: list[list[int]] | None = None
    lens: dict | None = None
    format_version: int = FORMAT_VERSION
    tool_version: str = __version__

    @classmethod
    def from_source(
        cls, info: SourceInfo, *, b: int, exposure_requested_us: int | None, start_time_utc: str
    ) -> SessionManifest:
        """Start a manifest from what a source knows about its camera."""
        return cls(
            camera=info.camera,
            serial=info.serial,
            width=info.width,
            height=info.height,
            color_filter=info.color_filter.value,
            source=info.origin,
            b=b,
            firmware_version=info.firmware_version,
            logic_version=info.logic_version,
            device_config=dict(info.extra),
            exposure_requested_us=exposure_requested_us,
            start_time_utc=start_time_utc,
        )

    @property
    def filter_pattern(self) -> ColorFilter:
        """The colour filter as a :class:`ColorFilter`."""
        return ColorFilter(self.color_filter)

    def to_json(self) -> str:
        """Serialise as indented JSON (values JSON lacks, such as enums, as their text)."""
        return json.dumps(dataclasses.asdict(self), indent=2, default=_json_text) + "\n"

    @classmethod
    def from_json(cls, text: str, *, where: str = MANIFEST_NAME) -> SessionManifest:
        """Parse JSON written by :meth:`to_json`.

        Raises:
            SessionError: not JSON, a newer format version, missing or unknown fields.
        """
        try:
            values = json.loads(text)
        except json.JSONDecodeError as error:
            raise SessionError(f"{where}: not valid JSON ({error})") from error
        if not isinstance(values, dict):
            raise SessionError(f"{where}: expected a JSON object at the top level")
        version = values.get("format_version")
        if version != FORMAT_VERSION:
            raise SessionError(
                f"{where}: session format version {version!r}, this seecap reads version "
                f"{FORMAT_VERSION}: use the seecap version that wrote it"
            )
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        missing = sorted(f for f in _REQUIRED if f not in values)
        if unknown or missing:
            raise SessionError(
                f"{where}: "
                + "; ".join(
                    [f"unknown field {name!r}" for name in unknown]
                    + [f"missing field {name!r}" for name in missing]
                )
            )
        _check_types(values, _FIELD_TYPES, where)
        drops = values.get("drops", {})
        if not isinstance(drops, dict):
            raise SessionError(f"{where}: field 'drops' must be an object, not {drops!r}")
        _check_types(drops, dict.fromkeys(drops, (int,)), f"{where}: drops")
        try:
            values["drops"] = DropCounters(**drops)
        except TypeError as error:
            raise SessionError(f"{where}: drops: unexpected field ({error})") from error
        manifest = cls(**values)
        if manifest.status not in _STATUSES:
            raise SessionError(f"{where}: status {manifest.status!r} is not one of {_STATUSES}")
        _check_values(manifest, where)
        return manifest


_SIZE = Bounds(1, 8192, "pixels", integer=True)
_COUNT = Bounds(0, 2**62, integer=True)
_DURATION_US = Bounds(0, 30 * 86_400 * 1_000_000, "µs", integer=True)


def _is_time(value) -> bool:
    """A device time in µs: a whole number (not a bool) of a plausible size."""
    return isinstance(value, int) and not isinstance(value, bool) and abs(value) < 2**62


_VALUE_BOUNDS = {
    "width": _SIZE,
    "height": _SIZE,
    "b": BINS,
    "frame_count": _COUNT,
    "event_count": _COUNT,
    "exposure_requested_us": _DURATION_US,
    "exposure_measured_us": _DURATION_US,
    "exposure_assumed_us": _DURATION_US,
}
"""The values each numeric field of ``session.json`` may hold (None aside, where allowed)."""


def _check_values(manifest: SessionManifest, where: str) -> None:
    """Raise on the first field outside its range, or a colour filter seecap does not know."""
    for name, bounds in _VALUE_BOUNDS.items():
        value = getattr(manifest, name)
        problem = None if value is None else bounds.problem(f"field {name!r}", value)
        if problem is not None:
            raise SessionError(f"{where}: {problem}")
    for name, value in dataclasses.asdict(manifest.drops).items():
        problem = _COUNT.problem(f"field 'drops.{name}'", value)
        if problem is not None:
            raise SessionError(f"{where}: {problem}")
    for gap in manifest.event_gaps_us or ():
        if not (isinstance(gap, list) and len(gap) == 2 and all(_is_time(v) for v in gap)):
            raise SessionError(f"{where}: field 'event_gaps_us' holds {gap!r}, not [start, end]")
    if manifest.lens is not None:
        try:
            Lens.from_json(manifest.lens, f"{where}: field 'lens'")
        except UsageError as error:
            raise SessionError(str(error)) from None
    if manifest.color_filter not in {pattern.value for pattern in ColorFilter}:
        names = ", ".join(pattern.value for pattern in ColorFilter)
        raise SessionError(
            f"{where}: field 'color_filter' {manifest.color_filter!r} is not one of {names}"
        )


_REQUIRED = ("camera", "serial", "width", "height", "color_filter", "source", "b")
_JSON_TYPES: dict[str, tuple[type, ...]] = {
    "int": (int,),
    "str": (str,),
    "int | None": (int, type(None)),
    "dict": (dict,),
    "list[str]": (list,),
    "list[list[int]] | None": (list, type(None)),
    "dict | None": (dict, type(None)),
}
"""The JSON types a field's annotation allows (``drops`` is checked on its own)."""
_FIELD_TYPES = {
    f.name: _JSON_TYPES[f.type] for f in dataclasses.fields(SessionManifest) if f.name != "drops"
}


def _check_types(values: dict, types: dict[str, tuple[type, ...]], where: str) -> None:
    """Raise on the first field whose JSON value is not of its type (a bool is not a number)."""
    for name, allowed in types.items():
        if name not in values:
            continue
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, allowed):
            wanted = " or ".join("null" if t is type(None) else t.__name__ for t in allowed)
            raise SessionError(f"{where}: field {name!r} must be {wanted}, not {value!r}")


def _json_text(value) -> object:
    """JSON form of the device facts JSON has no type for (enums, paths, numpy scalars)."""
    if isinstance(value, enum.Enum):
        return value.value
    if hasattr(value, "item"):
        return value.item()
    return str(value)


def read_manifest(session_dir: Path) -> SessionManifest:
    """Read ``session.json`` of a session folder.

    Raises:
        SessionError: the file is missing or malformed.
    """
    path = Path(session_dir) / MANIFEST_NAME
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError as error:
        raise SessionError(
            f"{path} not found: {session_dir} is not a session folder (record one with "
            "`seecap record`)"
        ) from error
    except UnicodeDecodeError as error:
        raise SessionError(
            f"{path}: byte offset {error.start} is not UTF-8 text ({error.reason}); the file is "
            "damaged: restore it from a copy, or rewrite that field by hand"
        ) from error
    return SessionManifest.from_json(text, where=str(path))


def write_manifest(session_dir: Path, manifest: SessionManifest) -> None:
    """Write ``session.json`` atomically (temporary file, fsync, rename)."""
    path = Path(session_dir) / MANIFEST_NAME
    temporary = path.with_name(f".{MANIFEST_NAME}.tmp")
    with open(temporary, "w", encoding="utf-8") as stream:
        stream.write(manifest.to_json())
        stream.flush()
        os.fsync(stream.fileno())
    os.replace(temporary, path)
