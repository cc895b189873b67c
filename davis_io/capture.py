"""``seecap record``'s sources: one registry of camera, AEDAT replay and emulator, then recording.

Each source kind opens a packet source from a :class:`CaptureRequest`; the recorder in
``davis_io.session`` takes any of them through the one packet-source interface and never
imports a source itself. A kind may leave something beside the session once it is recorded
(the emulator writes its ground truth into ``truth/``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from davis_io.chips import DEFAULT_FRAME_GAP_US
from davis_io.errors import DeviceError, UsageError
from davis_io.session.recorder import RecordingResult, record
from davis_io.types import ColorFilter, PacketSource

__all__ = [
    "NO_CAMERA_ADVICE",
    "SOURCE_KINDS",
    "WITHOUT_CAMERA",
    "CaptureRequest",
    "SourceKind",
    "open_capture_source",
    "record_capture",
]

WITHOUT_CAMERA = (
    "to record without a camera, `--replay FILE.aedat4` replays a recording and "
    "`--emulate room` films a built-in scene"
)
NO_CAMERA_ADVICE = (
    "plug a DAVIS346 or DAVIS240 into a USB port (check it with `seecap devices`; on Linux "
    f"install the permissions rule with `sudo seecap udev --install`); {WITHOUT_CAMERA}"
)


@dataclass(frozen=True)
class CaptureRequest:
    """What to record from, as given on the command line.

    Attributes:
        exposure_us: APS exposure to apply, µs (required for a camera); for a replay, the
            exposure of frames the file states none for.
        frame_interval_us: time between frame starts, µs (None: exposure + 50 ms).
        frames: frames to record (None: until stopped, or all of a replay / emulation).
        serial: camera serial number (None: the only camera attached).
        replay: AEDAT file to replay instead of a camera.
        emulate: built-in scene to film with the emulator instead of a camera.
        sensor: the emulator's sensor, ``default`` or ``random`` (drawn from ``seed``).
        seed: the emulator's seed (shake, pixel mismatch, noise and a random sensor).
        color_filter: the replayed sensor's colour filter, for a file that does not state it
            (None: the file's).
        event_window_us: the emulator keeps only the events this near an exposure, µs (0: all).
        still_frames: the emulator holds the camera still for this many frames mid-recording.
        exposure_steps: the emulator's auto exposure, each frame a share of the exposure in
            turn (empty: every frame the exposure).
        lens: the emulator's lens: ``pinhole``, ``random`` or OpenCV's ``k1,k2,p1,p2[,k3]``.
        model: the emulated camera model, a key of :data:`~davis_io.chips.SENSOR_SIZES`: its
            whole array, mono where the model was made mono only (None: a DAVIS346).
    """

    exposure_us: int | None = None
    frame_interval_us: int | None = None
    frames: int | None = None
    serial: str | None = None
    replay: Path | None = None
    emulate: str | None = None
    sensor: str = "default"
    seed: int = 0
    color_filter: ColorFilter | None = None
    event_window_us: int = 0
    still_frames: int = 0
    exposure_steps: tuple[float, ...] = ()
    lens: str = "pinhole"
    model: str | None = None

    @property
    def kind(self) -> str:
        """``replay``, ``emulate`` or ``usb``.

        Raises:
            UsageError: both a replay file and a scene to emulate.
        """
        if self.replay is not None and self.emulate is not None:
            raise UsageError("--replay and --emulate exclude each other: give one source")
        if self.replay is not None:
            return "replay"
        return "emulate" if self.emulate is not None else "usb"

    @property
    def applied_exposure_us(self) -> int | None:
        """The exposure the source is set to (None for a replay: the file decides)."""
        return None if self.replay is not None else self.exposure_us

    def interval_us(self) -> int:
        """Frame interval to apply, µs."""
        return self.frame_interval_us or (self.exposure_us or 0) + DEFAULT_FRAME_GAP_US


def _open_replay(request: CaptureRequest) -> PacketSource:
    from davis_io.aedat import open_recording
    from davis_io.aedat.colour_frames import RawMosaicFrames

    return RawMosaicFrames(open_recording(request.replay), request.color_filter)


def _open_emulator(request: CaptureRequest) -> PacketSource:
    from davis_io.emulator import EmulatedCamera
    from davis_io.emulator.config import model_settings

    settings = {
        "sensor": request.sensor,
        "seed": request.seed,
        "event_window_us": request.event_window_us,
        "still_frames": request.still_frames,
        "exposure_steps": request.exposure_steps,
        "lens": request.lens,
    }
    if request.exposure_us is not None:
        settings["exposure_us"] = request.exposure_us
        settings["frame_interval_us"] = request.interval_us()
    if request.frames is not None:
        settings["frames"] = request.frames
    if request.model is not None:
        settings.update(model_settings(request.model))
    return EmulatedCamera(request.emulate, **settings)


def _open_camera(request: CaptureRequest) -> PacketSource:
    if request.exposure_us is None:
        raise UsageError("recording from a camera needs --exposure (for example --exposure 0.15)")
    try:
        from davis_io.usb import ApsConfig, DavisConfig, open_camera
    except ImportError as error:
        message = f"camera support is not available ({error}): {NO_CAMERA_ADVICE}"
        raise DeviceError(message) from error
    aps = ApsConfig(exposure_us=request.exposure_us, frame_interval_us=request.interval_us())
    try:
        return open_camera(request.serial, DavisConfig(aps=aps))
    except DeviceError as error:
        raise DeviceError(f"{error}; {WITHOUT_CAMERA}") from error


@dataclass(frozen=True)
class SourceKind:
    """How to open one kind of source, and what it leaves beside a recorded session.

    Attributes:
        open: the packet source of a request.
        after_recording: ``after_recording(source, session_folder)``, or None.
    """

    open: Callable[[CaptureRequest], PacketSource]
    after_recording: Callable[[PacketSource, Path], None] | None = None


SOURCE_KINDS: dict[str, SourceKind] = {
    "usb": SourceKind(_open_camera),
    "replay": SourceKind(_open_replay),
    "emulate": SourceKind(_open_emulator, lambda camera, folder: camera.write_truth(folder)),
}
"""Every source ``seecap record`` can read, by :attr:`CaptureRequest.kind`."""


def open_capture_source(request: CaptureRequest) -> PacketSource:
    """Open the replay file, the emulator or the camera the request names.

    Raises:
        UsageError: both --replay and --emulate, or a camera without --exposure.
        DeviceError: no camera found (with advice on what to plug in or which flag to use).
    """
    return SOURCE_KINDS[request.kind].open(request)


def record_capture(request: CaptureRequest, out_dir: Path, **options) -> RecordingResult:
    """Open the requested source and record it into ``out_dir`` (emulator: with ``truth/``).

    Args:
        request: the source and its settings.
        out_dir: the session folder to create.
        **options: passed to :func:`davis_io.session.recorder.record` (``bins``,
            ``duration_us``, ``overwrite``, ``status_callback``, ``preview``).

    Returns:
        The recording result.
    """
    kind = SOURCE_KINDS[request.kind]
    source = kind.open(request)
    result = record(
        source,
        out_dir,
        exposure_us=request.applied_exposure_us,
        unstated_exposure_us=request.exposure_us,
        frames=request.frames,
        **options,
    )
    if kind.after_recording is not None:
        kind.after_recording(source, result.folder)
    return result
