"""``seecap record``: frames and events in sync into a session folder (camera, replay, emulator)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from davis_io.chips import DEFAULT_MODEL, SENSOR_SIZES
from davis_io.errors import UsageError
from davis_io.session.bounds import Bounds
from davis_io.session.defaults import BINS, DEFAULT_BINS, EXPOSURE_S, FRAME_COUNT, SEED
from davis_io.session.units import parse_duration_us
from davis_io.types import ColorFilter

__all__ = ["HELP", "add_arguments", "run"]

HELP = "record APS frames and DVS events in sync into a session folder"

FRAME_INTERVAL_S = Bounds(1e-6, 60.0, "s")
"""Time between frame starts: a frame a minute at the longest."""

STILL_FRAMES = Bounds(0, 10_000, "frames", integer=True)
"""Frames the emulated camera may be held still for."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap record``."""
    parser.add_argument(
        "--exposure",
        help="APS exposure: seconds (0.15), 150ms or 150000us; with --replay, the exposure of "
        "frames the file states none for (default: half the time to the next frame)",
    )
    parser.add_argument("--out", type=Path, help="session folder (default: session-<UTC time>)")
    limit = parser.add_mutually_exclusive_group()
    limit.add_argument(
        "--frames", type=FRAME_COUNT.argument("--frames"), help="stop after this many frames"
    )
    limit.add_argument("--duration", help="stop after this much time: seconds, ms or us")
    parser.add_argument(
        "--bins",
        type=BINS.argument("--bins"),
        default=DEFAULT_BINS,
        help=f"event bins per exposure (default {DEFAULT_BINS})",
    )
    parser.add_argument(
        "--frame-interval", help="time between frame starts (default: exposure + 50ms)"
    )
    parser.add_argument("--serial", help="camera serial number when several are attached")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--replay", type=Path, help="replay an AEDAT 2.0/3.1/4.0 file instead")
    source.add_argument(
        "--emulate", metavar="SCENE", help="film a built-in scene (room, lamp, corridor)"
    )
    parser.add_argument(
        "--sensor",
        choices=("default", "random"),
        default="default",
        help="with --emulate: the default sensor, or one drawn at random from --seed (its "
        "values go only into the session's truth/)",
    )
    parser.add_argument(
        "--seed",
        type=SEED.argument("--seed"),
        default=0,
        help="with --emulate: seed of the shake, noise and sensor",
    )
    parser.add_argument(
        "--event-window",
        metavar="DURATION",
        help="with --emulate: keep only the events this near an exposure (3ms: a recording made "
        "view by view, or a stream with long gaps; default: every event)",
    )
    parser.add_argument(
        "--still-frames",
        type=STILL_FRAMES.argument("--still-frames"),
        default=0,
        help="with --emulate: hold the camera still (no move, no shake) for this many frames "
        "in the middle of the recording",
    )
    parser.add_argument(
        "--auto-exposure",
        type=_exposure_shares,
        default=(),
        metavar="SHARES",
        help="with --emulate: expose each frame for these shares of --exposure in turn, as a "
        "camera's auto exposure does (1,0.5,0.25; the gain stays --exposure's, so a shorter "
        "frame is darker; default: every frame for --exposure)",
    )
    parser.add_argument(
        "--camera",
        choices=tuple(SENSOR_SIZES),
        metavar="MODEL",
        help="with --emulate: the camera model, its whole array: DAVIS346 (346x260, RGGB unless "
        f"--sensor random draws mono) or DAVIS240 (240x180, mono) (default: {DEFAULT_MODEL})",
    )
    parser.add_argument(
        "--lens",
        default="pinhole",
        metavar="pinhole|random|K1,K2,P1,P2[,K3]",
        help="with --emulate: the lens's distortion (OpenCV's model; random: a barrel "
        "distortion drawn from --seed; default: none)",
    )
    parser.add_argument(
        "--color-filter",
        choices=[c.value for c in ColorFilter if c.is_color],
        help="with --replay: the sensor's colour filter, for a file of demosaiced colour frames "
        "that does not state it (a colour DAVIS346 is RGGB)",
    )
    parser.add_argument(
        "--camera-calibration",
        type=Path,
        metavar="FILE",
        help="the camera's lens, stored with the session for its poses and fit: DV's or "
        "OpenCV's calibration (XML or YAML), COLMAP's cameras.txt or JSON with fx, fy, cx, cy",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing session")
    parser.add_argument(
        "--preview", type=Path, help="PNG refreshed with the newest frame and its events"
    )


def run(args: argparse.Namespace) -> int:
    """Record, printing a live status line and per-frame warnings on stderr."""
    from davis_io.capture import CaptureRequest, record_capture
    from davis_io.session.folder import default_session_name

    emulator_only = (
        args.sensor != "default"
        or args.seed
        or args.event_window
        or args.still_frames
        or args.auto_exposure
        or args.lens != "pinhole"
        or args.camera
    )
    if args.emulate is None and emulator_only:
        raise UsageError(
            "--sensor, --seed, --event-window, --still-frames, --auto-exposure, --lens and "
            "--camera describe the emulated camera: use them with --emulate"
        )
    if args.replay is None and args.color_filter is not None:
        raise UsageError("--color-filter describes a replayed file's sensor: use it with --replay")
    request = CaptureRequest(
        exposure_us=_duration(args.exposure, "--exposure", EXPOSURE_S),
        frame_interval_us=_duration(args.frame_interval, "--frame-interval", FRAME_INTERVAL_S),
        frames=args.frames,
        serial=args.serial,
        replay=args.replay,
        emulate=args.emulate,
        sensor=args.sensor,
        seed=args.seed,
        color_filter=None if args.color_filter is None else ColorFilter(args.color_filter),
        event_window_us=_duration(args.event_window, "--event-window", EXPOSURE_S) or 0,
        still_frames=args.still_frames,
        exposure_steps=args.auto_exposure,
        lens=args.lens,
        model=args.camera,
    )
    out_dir = args.out or Path(default_session_name())
    printer = _StatusPrinter()
    result = record_capture(
        request,
        out_dir,
        bins=args.bins,
        duration_us=_duration(args.duration, "--duration"),
        overwrite=args.overwrite,
        status_callback=printer,
        preview=args.preview,
        camera_calibration=args.camera_calibration,
    )
    if printer.live:
        print(file=sys.stderr)  # end the status line
    printer.warn(result.warnings[printer.warned :])  # those of the recording's end
    print(_summary(result))
    if result.stop_signal:
        return 128 + result.stop_signal
    if result.status != "complete":
        print(f"seecap: warning: record: {result.manifest.stop_reason}", file=sys.stderr)
        return 1
    return 0


def _duration(text: str | None, what: str, bounds: Bounds | None = None) -> int | None:
    """``text`` in µs (None stays None), within ``bounds`` (in seconds) when given."""
    if text is None:
        return None
    value_us = parse_duration_us(text, what=what)
    if bounds is not None:
        bounds.check(what, value_us / 1e6)
    return value_us


class _StatusPrinter:
    """Rewrites one status line on a terminal (a line every 5 s in a log); warnings on their own."""

    LOG_INTERVAL_S = 5.0

    def __init__(self):
        self.live = sys.stderr.isatty()
        self.logged_at = -self.LOG_INTERVAL_S
        self.warned = 0

    def warn(self, warnings: list[str]) -> None:
        """Print each warning on a line of its own."""
        for warning in warnings:
            print(("\r\033[K" if self.live else "") + f"warning: {warning}", file=sys.stderr)
        self.warned += len(warnings)

    def __call__(self, status) -> None:
        from davis_io.session.status import format_status_line

        self.warn(status.warnings)
        line = format_status_line(status)
        if self.live:
            print(f"\r\033[K{line}", end="", file=sys.stderr, flush=True)
        elif status.elapsed_s - self.logged_at >= self.LOG_INTERVAL_S:
            print(line, file=sys.stderr, flush=True)
            self.logged_at = status.elapsed_s


def _summary(result) -> str:
    manifest = result.manifest
    requested = manifest.exposure_requested_us
    measured = manifest.exposure_measured_us
    assumed = manifest.exposure_assumed_us
    lines = [
        f"session   {result.folder} ({manifest.status}"
        + (f": {manifest.stop_reason})" if manifest.stop_reason else ")"),
        f"source    {manifest.source}  {manifest.camera} {manifest.width}x{manifest.height}",
        f"frames    {manifest.frame_count}   events {manifest.event_count}   bins b={manifest.b}",
        "exposure  applied "
        + (f"{requested / 1000:.3f} ms" if requested is not None else "- (from the file)")
        + "   measured (median) "
        + (f"{measured / 1000:.3f} ms" if measured is not None else "- (no frame)")
        + (f"   assumed {assumed / 1000:.3f} ms (not stated)" if assumed is not None else ""),
        f"drops     {manifest.drops.total_events} events, {manifest.drops.queue_frames} frames; "
        f"{manifest.drops.frames_events_lost} frames flagged for lost events",
    ]
    if result.warnings:
        lines.append(f"warnings  {len(result.warnings)} (printed above)")
    return "\n".join(lines)


def _exposure_shares(text: str) -> tuple[float, ...]:
    """``--auto-exposure``'s comma-separated shares of the exposure, each in (0, 1]."""
    try:
        shares = tuple(float(part) for part in text.split(","))
    except ValueError:
        shares = ()
    if not shares or any(not 0 < share <= 1 for share in shares):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a list of shares of the exposure in (0, 1], e.g. 1,0.5,0.25"
        )
    return shares
