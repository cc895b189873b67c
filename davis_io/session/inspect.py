"""``seecap inspect`` for session folders: summary, per-frame table, and repair after a crash."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from davis_io.errors import SessionError
from davis_io.lens import Lens
from davis_io.session.layout import EVENT_FIELDS, FILE_FORMAT, H5_NAME, create_image_dataset
from davis_io.session.lock import writer_lock
from davis_io.session.manifest import (
    STATUS_INTERRUPTED,
    STATUS_RECORDING,
    SessionManifest,
    read_manifest,
    write_manifest,
)
from davis_io.session.store import Session
from davis_io.session.writer import RESERVE_NAME

__all__ = [
    "RepairReport",
    "describe_session",
    "repair_session",
    "session_report",
]

_NOTES_SHOWN = 5
_REPAIRED_REASON = "the recording never closed (killed, crashed or unplugged); repaired"


def describe_session(path: Path | str, args: argparse.Namespace) -> int:
    """``seecap inspect SESSION``: print the report; honours ``--repair``, ``--frames``, ``--json``.

    Args:
        path: the session folder.
        args: parsed options; ``repair``, ``frames`` and ``json`` are read when present.

    Returns:
        The exit code, 0.
    """
    print(
        session_report(
            path,
            frames=getattr(args, "frames", False),
            repair=getattr(args, "repair", False),
            as_json=getattr(args, "json", False),
        )
    )
    return 0


def session_report(path: Path | str, *, frames: bool, repair: bool, as_json: bool) -> str:
    """Summary of a session (after repairing it when ``repair``), with a frame table if asked."""
    lines = [repair_session(path).describe()] if repair else []
    with Session.open(path) as session:
        session.check_coordinates()
        summary = _summary(session)
        table = _frame_rows(session) if frames else None
        calibration = session.calibration()
    if as_json:
        document = {"session": summary, **({"frames": table} if table is not None else {})}
        return "\n".join([*lines, json.dumps(document, indent=2)])
    for key, value in summary.items():
        if key == "source_notes":
            lines.extend(f"{'source note':28s} {note}" for note in _shown_notes(value))
        elif key == "calibration" and calibration is not None:
            # Which values were measured and which assumed (and why), one per line.
            shown = calibration.summary().split("\nmethod: ")[0].splitlines()
            lines.extend(f"{key if i == 0 else '':28s} {line}" for i, line in enumerate(shown))
        else:
            lines.append(f"{key:28s} {value}")
    if table is not None:
        lines.append(_format_table(table))
    return "\n".join(lines)


def _shown_notes(notes: list[str]) -> list[str]:
    """The first notes, and how many more ``--json`` lists."""
    more = len(notes) - _NOTES_SHOWN
    return notes[:_NOTES_SHOWN] + ([f"... and {more} more (--json lists them)"] if more > 0 else [])


def _summary(session: Session) -> dict:
    """Key facts of a session as a JSON-safe dictionary."""
    manifest = session.manifest
    table = session.frames_table()
    counts = session.window_event_counts()
    return {  # how the recording ended first: a truncated or interrupted one says so at once
        "status": manifest.status + (f" ({manifest.stop_reason})" if manifest.stop_reason else ""),
        "needs_repair": session.needs_repair,
        "source_notes": manifest.source_notes,
        "folder": str(session.folder),
        "camera": f"{manifest.camera} serial {manifest.serial or '?'}",
        "resolution": f"{manifest.width}x{manifest.height} ({manifest.color_filter})",
        "lens": _lens(manifest.lens),
        "source": manifest.source,
        "started_utc": manifest.start_time_utc,
        "stopped_utc": manifest.stop_time_utc,
        "frames": session.frame_count,
        "events": session.event_count,
        "exposure_requested_us": manifest.exposure_requested_us,
        "exposure_measured_us": _median(table.exposure_us),
        "exposure_assumed_us": manifest.exposure_assumed_us,
        "exposure_range_us": _range(table.exposure_us),
        "frames_events_lost": int(table.events_lost.sum()),
        "event_gaps": _gaps(session.event_gaps()),
        "events_per_exposure_median": None if counts is None else _median(counts),
        "bins_stored": session.stored_bins(),
        "hdf5_filters": _filters(session.filters()),
        "drops": dataclasses.asdict(manifest.drops),
        "calibration": _calibration(session),
        "truth": str(session.truth_dir) if session.truth_dir else None,
    }


def _lens(stated: dict | None) -> str:
    """The lens the recording states, or that it states none."""
    if stated is None:
        return "not stated (the poses estimate one; --camera-calibration gives it)"
    return Lens.from_json(stated).summary()


def _calibration(session: Session) -> dict | None:
    """The measured sensor facts, or None before ``seecap calibrate`` (or a fit) ran."""
    calibration = session.calibration()
    if calibration is None:
        return None
    facts = calibration.facts()
    return {
        key: round(value, 4) if isinstance(value, float) else value
        for key, value in facts.items()
        if key != "method"
    }


def _filters(filters: dict[str, list[str]]) -> str:
    """Which compression filters the file uses, and whether any HDF5 build reads them all."""
    counts = ", ".join(f"{kind} ({len(names)} datasets)" for kind, names in sorted(filters.items()))
    if "lzf" not in filters:
        return f"{counts}; any HDF5 build reads them"
    return (
        f"{counts}; the recording's LZF needs h5py or HDF5's LZF plug-in (h5dump, HDFView, "
        "MATLAB); everything written after it is gzip or plain"
    )


def _gaps(gaps: np.ndarray) -> str:
    """How many gaps the event stream has and how long they are."""
    if len(gaps) == 0:
        return "none"
    lengths_ms = (gaps[:, 1] - gaps[:, 0]) / 1000
    return (
        f"{len(gaps)}, {lengths_ms.min():.1f}-{lengths_ms.max():.1f} ms (no frame pair, bin or "
        "event loss spans them)"
    )


def _median(values: np.ndarray) -> int | None:
    return int(np.median(values)) if len(values) else None


def _range(exposures_us: np.ndarray) -> str:
    """The shortest and longest exposure, or that every frame had the same (or none was)."""
    if len(exposures_us) == 0:
        return "no frame"
    low, high = int(exposures_us.min()), int(exposures_us.max())
    return "every frame the same" if low == high else f"{low}..{high} (an auto exposure)"


def _frame_rows(session: Session) -> list[dict]:
    """One row per frame: times, exposure, events in the window, loss flag."""
    table = session.frames_table()
    counts = session.window_event_counts()
    if counts is None:
        counts = [None] * len(table.events_lost)
    return [
        {
            "frame": index,
            "exposure_start_us": int(table.exposure_start_us[index]),
            "exposure_end_us": int(table.exposure_end_us[index]),
            "exposure_us": int(table.exposure_us[index]),
            "readout_us": int(table.readout_end_us[index] - table.readout_start_us[index]),
            "events": None if counts[index] is None else int(counts[index]),
            "events_lost": bool(table.events_lost[index]),
        }
        for index in range(len(table.events_lost))
    ]


def _format_table(rows: list[dict]) -> str:
    header = (
        f"{'frame':>5} {'exposure start µs':>18} {'exposure µs':>11} {'readout µs':>10} "
        f"{'events':>9} lost"
    )
    body = [
        f"{r['frame']:>5} {r['exposure_start_us']:>18} {r['exposure_us']:>11} "
        f"{r['readout_us']:>10} {r['events'] if r['events'] is not None else '-':>9} "
        f"{'yes' if r['events_lost'] else 'no'}"
        for r in rows
    ]
    return "\n".join([header, *body])


@dataclass(frozen=True)
class RepairReport:
    """What :func:`repair_session` did."""

    folder: Path
    rewrote_h5: bool
    frames: int
    events: int
    status_before: str

    def describe(self) -> str:
        """One line for the user."""
        if not self.rewrote_h5 and self.status_before != STATUS_RECORDING:
            return f"{self.folder}: nothing to repair"
        action = "rewrote session.h5 and " if self.rewrote_h5 else ""
        return (
            f"{self.folder}: {action}marked the session interrupted "
            f"({self.frames} complete frames, {self.events} events kept)"
        )


def repair_session(path: Path | str) -> RepairReport:
    """Make a session whose recorder never closed it normal again.

    A killed writer leaves ``session.h5`` readable only in HDF5 SWMR mode and the manifest at
    ``recording``. The repair copies every complete record into a fresh ``session.h5`` (trimming
    rows written after the last complete frame) and marks the manifest ``interrupted``.

    The repair holds the session's writer lock: a recording still running is refused, not cut.

    Raises:
        SessionError: not a session, or the data cannot be read.
        SessionBusy: another process writes the session (a live recording).
    """
    folder = Path(path)
    read_manifest(folder)  # not a session: say so before creating a lock in the folder
    with writer_lock(folder, "repairing the session"):
        return _repair(folder)


def _repair(folder: Path) -> RepairReport:
    (folder / RESERVE_NAME).unlink(missing_ok=True)  # a killed recorder's room to close in
    manifest = read_manifest(folder)
    status_before = manifest.status
    with Session.open(folder) as session:
        needs_copy = session.needs_repair
        frames, events = session.frame_count, session.event_count
    if needs_copy:
        _rewrite_h5(folder, frames, events, manifest)
    if status_before == STATUS_RECORDING or needs_copy:
        with Session.open(folder) as session:
            table = session.frames_table()
        manifest.status = STATUS_INTERRUPTED
        manifest.stop_reason = _REPAIRED_REASON
        manifest.frame_count, manifest.event_count = frames, events
        if len(table.exposure_us):
            manifest.exposure_measured_us = int(np.median(table.exposure_us))
        if not manifest.stop_time_utc:
            stamp = os.path.getmtime(folder / H5_NAME)
            stopped = datetime.fromtimestamp(stamp, UTC)
            manifest.stop_time_utc = stopped.isoformat(timespec="seconds")
        write_manifest(folder, manifest)
    return RepairReport(folder, needs_copy, frames, events, status_before)


def _rewrite_h5(folder: Path, frames: int, events: int, manifest: SessionManifest) -> None:
    """Copy the SWMR file into a new one, trimmed to ``frames`` frames and ``events`` events.

    A recorder killed before its first frame never created ``/frames/image``: the copy gets
    an empty 16-bit one, so every session has the full layout.
    """
    source_path, target_path = folder / H5_NAME, folder / f".{H5_NAME}.repair"
    try:
        with (
            h5py.File(source_path, "r", swmr=True) as source,
            h5py.File(target_path, "w", libver=FILE_FORMAT) as target,
        ):
            for name in source:
                source.copy(source[name], target, name=name)
            _trim(target, frames, events)
            if "image" not in target.require_group("frames"):
                create_image_dataset(
                    target,
                    width=manifest.width,
                    height=manifest.height,
                    image_dtype=np.uint16,
                    bit_depth=10,
                )
    except OSError as error:
        target_path.unlink(missing_ok=True)
        raise SessionError(f"{source_path}: cannot repair ({error})") from error
    os.replace(target_path, source_path)


def _trim(h5: h5py.File, frames: int, events: int) -> None:
    """Cut every per-frame and per-event dataset to the complete count."""
    for name in EVENT_FIELDS if "events" in h5 else ():
        h5["events"][name].resize(events, axis=0)
    for dataset in h5["frames"].values() if "frames" in h5 else ():
        dataset.resize(frames, axis=0)
    for group in h5.get("bins", {}).values():
        for dataset in group.values():
            dataset.resize(min(frames, dataset.shape[0]), axis=0)
