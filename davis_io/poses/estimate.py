"""``estimate_poses``: EDI latent frames of a session, COLMAP with recovery, poses and a report."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np

from davis_io.calibration.session_calibration import session_calibration
from davis_io.geometry import interpolate_poses
from davis_io.lens import COEFFICIENT_NAMES, Lens, read_camera_calibration
from davis_io.poses.colmap import ColmapError, SparseModel
from davis_io.poses.latent import calibrated_response, latent_images, sharpness
from davis_io.poses.nerfstudio import latent_frame_name
from davis_io.poses.recovery import Outcome, reconstruct_with_recovery
from davis_io.session import (
    DEFAULT_BINS,
    DEFAULT_THRESHOLD,
    SensorCalibration,
    Session,
    SessionPoses,
    contrast_bins,
    default_calibration,
    writer_lock,
)
from davis_io.session.writer import check_free_space, not_written

__all__ = [
    "PoseReport",
    "estimate_poses",
    "made_with",
    "stated_lens",
]

Progress = Callable[[str, int, int], None]
"""``progress(stage, done, total)``; ``total`` is 0 when unknown."""

COLMAP_BYTES_PER_PIXEL = 8
"""Disk a latent frame takes in ``colmap/``, per pixel, with room to spare: measured 0.65 MB per
346 x 260 frame (its PNG 0.19 MB, its features and matches in the database 0.39 MB, its share of
the sparse models 0.07 MB), 7.2 bytes per pixel."""


@dataclass(frozen=True)
class PoseReport:
    """How pose estimation went.

    Attributes:
        registered: latent frames COLMAP registered.
        total: latent frames written (frames x (b+1)).
        reprojection_error_px: mean reprojection error, pixels.
        track_counts: ``(F, b+1)`` 3-D points seen by each latent frame (0: not registered).
        strategy: the recovery strategy whose model was kept.
        tried: strategies run, in order.
        threshold: mean ON/OFF contrast threshold the EDI used, natural-log units per event.
        threshold_source: the calibration's source: ``measured``, ``given`` or ``default``.
        intrinsics: ``(fx, fy, cx, cy)`` pixels.
        bounds: near and far depth of the sparse points.
        latent_sensor: the sensor values the kept latent frames were made with (the
            calibration's source, ``given`` or ``nominal``).
        compared: what COLMAP said of each set of latent frames tried, by label.
        distortion: OpenCV's coefficients of the lens the poses were made with (empty: a
            pinhole).
        sparse_model: the kept model's folder inside ``colmap/`` ("" when unknown).
    """

    registered: int
    total: int
    reprojection_error_px: float
    track_counts: np.ndarray
    strategy: str
    tried: tuple[str, ...]
    threshold: float
    threshold_source: str
    intrinsics: np.ndarray
    bounds: np.ndarray
    latent_sensor: str = ""
    compared: dict = field(default_factory=dict)
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sparse_model: str = ""

    @property
    def registered_fraction(self) -> float:
        """Share of latent frames registered."""
        return self.registered / self.total if self.total else 0.0

    def summary(self) -> str:
        """Several human-readable lines."""
        per_view = self.track_counts.sum(axis=1)
        return "\n".join(
            [
                f"registered {self.registered}/{self.total} latent frames "
                f"({100 * self.registered_fraction:.1f}%) with strategy {self.strategy} "
                f"(tried: {', '.join(self.tried)})",
                f"mean reprojection error {self.reprojection_error_px:.3f} px",
                "intrinsics fx {:.2f} fy {:.2f} cx {:.2f} cy {:.2f} px".format(*self.intrinsics)
                + _distortion_text(self.distortion),
                f"bounds near {self.bounds[0]:.3f} far {self.bounds[1]:.3f}",
                f"contrast threshold {self.threshold:.3f} ({self.threshold_source})",
                *self._comparison(),
                "tracks per view: " + " ".join(str(int(n)) for n in per_view),
            ]
        )

    def _comparison(self) -> list[str]:
        if len(self.compared) < 2:
            return []
        tried = "; ".join(
            f"{label}: {said['registered']} registered, tracks {said['mean_track_length']:.1f}, "
            f"{said['reprojection_error_px']:.3f} px"
            for label, said in self.compared.items()
        )
        return [f"latent frames kept: {self.latent_sensor} sensor values ({tried})"]

    def to_json(self) -> dict:
        """JSON-safe dictionary (arrays as lists)."""
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, np.ndarray):
                out[key] = value.tolist()
        return out

    @classmethod
    def from_json(cls, data: dict) -> PoseReport:
        """Inverse of :meth:`to_json`."""
        data = dict(data)
        data.pop("test_c2w", None)  # written by earlier versions, from the truth
        for key in ("track_counts", "intrinsics", "bounds", "distortion"):
            data[key] = np.asarray(data.get(key, []))
        data["tried"] = tuple(data["tried"])
        return cls(**data)


def _inside(folder: Path | None, trial_folder: Path) -> str:
    """``folder`` relative to its trial's folder (which becomes ``colmap/``), or ""."""
    if folder is None:
        return ""
    return folder.relative_to(trial_folder).as_posix()


def _distortion_text(distortion: np.ndarray) -> str:
    """``, k1 .. p2 ...`` of a distorted lens, nothing for a pinhole."""
    named = zip(COEFFICIENT_NAMES, np.asarray(distortion, float).ravel(), strict=False)
    return "".join(f", {name} {value:+.4g}" for name, value in named)


def _check_room(folder: Path, latent_frames: int, height: int, width: int) -> None:
    """Refuse to start when the disk cannot hold the latent frames and COLMAP's database.

    COLMAP's database aborts the process when SQLite cannot write, so a full disk must be
    caught before it starts, not where it happens.
    """
    what = f"estimating poses ({latent_frames} latent frames and COLMAP's database)"
    check_free_space(folder, what, latent_frames * height * width * COLMAP_BYTES_PER_PIXEL)


def _write_latent_frames(session, bins, response, image_dir, progress):
    image_dir.mkdir(parents=True, exist_ok=True)
    names, scores = [], []
    for i in range(session.frame_count):
        images = latent_images(
            session.frame(i),
            bins.calibrated[i],
            bins.weights[i],
            1.0,  # contrast bins: ln change, one unit per unit
            session.color_filter,
            response,
        )
        view = [latent_frame_name(i, k) for k in range(len(images))]
        for name, image in zip(view, images, strict=True):
            bgr = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
            if not cv2.imwrite(str(image_dir / name), bgr):
                raise not_written(
                    image_dir / name, "OpenCV could not write it", "run the poses again"
                )
        names.append(view)
        scores.append([sharpness(image) for image in images])
        progress("latent frames", i + 1, session.frame_count)
    return names, scores


def _session_poses(model: SparseModel, names, split_us: np.ndarray) -> SessionPoses:
    flat_names = [n for view in names for n in view]
    registered = np.array([n in model.c2w for n in flat_names]).reshape(split_us.shape)
    times = split_us.reshape(-1)
    known = np.flatnonzero(registered.reshape(-1))
    # Equal split times (two latent points at one instant) keep the first registered pose.
    known = known[np.concatenate([[True], np.diff(times[known]) > 0])]
    known_c2w = np.array([model.c2w[flat_names[j]] for j in known])
    c2w = interpolate_poses(times[known], known_c2w, times)
    for j in np.flatnonzero(registered.reshape(-1)):
        c2w[j] = model.c2w[flat_names[j]]
    return SessionPoses(
        c2w=c2w.reshape(*split_us.shape, 4, 4),
        registered=registered,
        intrinsics=model.intrinsics,
        distortion=model.distortion,
        bounds=model.bounds,
        time_us=split_us,
    )


def estimate_poses(
    session: Session | Path | str,
    *,
    b: int = DEFAULT_BINS,
    lens: Lens | None = None,
    force: bool = False,
    progress: Progress | None = None,
    threshold: float | None = None,
) -> PoseReport:
    """Estimate the camera pose at every latent time point of every frame and store it.

    Writes the EDI latent frames to ``session/colmap/images/``, reconstructs them with COLMAP
    (database and models kept in ``session/colmap/``), stores the poses for ``b`` in the
    session (unregistered latent time points interpolated in time and flagged) and the report
    in ``session/colmap/report.json``.

    Args:
        session: an open :class:`~davis_io.session.Session` or its folder.
        b: bins per exposure (b+1 latent frames per frame).
        lens: the camera's known lens (held fixed), or None for the one the session was
            recorded with (``session.json``'s ``lens``) or, without one, an estimated lens.
            Stored poses made with another lens are estimated again.
        force: recompute even when poses for ``b`` and their report exist.
        progress: ``progress(stage, done, total)`` for a progress display.
        threshold: contrast threshold (natural-log units per event) for ON, OFF and every
            pixel, or None for the session's calibration (measured first when missing).

    Returns:
        The :class:`PoseReport`.

    Raises:
        ColmapError: COLMAP could not reconstruct the frames (with advice).
        SessionError, UsageError: the session or an argument is not usable.
    """
    if not isinstance(session, Session):
        with Session.open(session) as opened:
            return estimate_poses(
                opened,
                b=b,
                lens=lens,
                force=force,
                progress=progress,
                threshold=threshold,
            )
    with writer_lock(session.folder, "estimating poses"):
        return _estimate(session, b, lens, force, progress, threshold)


def stated_lens(session: Path | str, calibration_file: Path | str) -> Lens:
    """The lens a calibration file states for the camera of ``session``.

    Raises:
        UsageError: the file cannot be read or is for another image size.
        SessionError: the session cannot be read.
    """
    with Session.open(session) as opened:
        size = opened.width, opened.height
    return read_camera_calibration(calibration_file, *size)


def made_with(poses: SessionPoses, lens: Lens) -> bool:
    """Whether ``poses`` were estimated with ``lens`` (its intrinsics and distortion)."""
    stated = Lens.pinhole(lens.width, lens.height, poses.intrinsics).with_distortion(
        poses.distortion
    )
    return stated.close_to(lens)


def _estimate(session, b, lens, force, progress, threshold) -> PoseReport:
    progress = progress or (lambda _stage, _done, _total: None)
    work_dir = session.folder / "colmap"
    report_path = work_dir / "report.json"
    stored = session.poses(b)
    if lens is None and session.manifest.lens is not None:
        lens = Lens.from_json(session.manifest.lens, f"{session.folder}/session.json")
    if lens is not None:
        lens = lens.for_size(session.width, session.height, "--camera-calibration")
        force = force or (stored is not None and not made_with(stored, lens))
    if not force and stored is not None and report_path.exists():
        return PoseReport.from_json(json.loads(report_path.read_text()))
    session.require_writable()
    if session.frame_count < 2:
        raise ColmapError(
            f"{session.folder}: {session.frame_count} frame(s); poses need at least 2 frames "
            "seen from different positions. Record longer"
        )
    progress("calibrating the sensor", 0, 0)
    candidates = _latent_sensors(session_calibration(session), threshold)
    _check_room(
        session.folder,
        session.frame_count * (b + 1) * len(candidates),
        session.height,
        session.width,
    )
    trials, failures = [], []
    for label, calibration in candidates:
        folder = work_dir if not trials and not failures else work_dir / label
        named = _labelled(progress, label) if len(candidates) > 1 else progress
        try:
            trials.append(_reconstruct(session, b, label, calibration, folder, lens, named))
        except ColmapError as error:
            failures.append(error)
    if not trials:
        raise failures[0]
    kept = max(trials, key=lambda trial: trial.quality)
    if kept.folder != work_dir:
        _promote(kept.folder, work_dir)
    poses = _session_poses(kept.outcome.model, kept.names, kept.split_us)
    session.write_poses(b, poses)
    model = kept.outcome.model
    report = PoseReport(
        registered=int(poses.registered.sum()),
        total=len(kept.names) * (b + 1),
        reprojection_error_px=model.reprojection_error_px,
        track_counts=np.array(
            [[model.track_counts.get(n, 0) for n in view] for view in kept.names]
        ),
        strategy=kept.outcome.strategy,
        tried=kept.outcome.tried,
        threshold=kept.calibration.threshold,
        threshold_source=kept.calibration.source,
        intrinsics=poses.intrinsics,
        distortion=poses.distortion,
        bounds=poses.bounds,
        latent_sensor=kept.label,
        sparse_model=_inside(model.folder, kept.folder),
        compared={trial.label: trial.colmap_says() for trial in trials},
    )
    report_path.write_text(json.dumps(report.to_json(), indent=1))
    return report


NOMINAL_FOR_POSES = "nominal"
"""Label (and ``colmap/`` subfolder) of the latent frames made with the nominal sensor."""


def _latent_sensors(calibration, threshold):
    """The sensor values to make latent frames with, by label.

    The calibration (with the given threshold, if any), and beside a calibration measured in
    part the nominal sensor, so that poses never pay for a doubtful value (the better
    reconstruction is kept). A calibration with assumed thresholds and no response curve is
    the nominal sensor already; one that holds a curve fitted beside them is not.
    """
    if threshold is not None:
        return [("given", calibration.with_threshold(threshold))]
    nominal_already = calibration.source in ("default", "assumed") and not len(
        calibration.response_value
    )
    if not calibration.assumed or nominal_already:
        return [(calibration.source, calibration)]
    nominal = default_calibration(
        DEFAULT_THRESHOLD,
        "the nominal sensor, tried for poses beside a calibration in part assumed",
    )
    return [(calibration.source, calibration), (NOMINAL_FOR_POSES, nominal)]


@dataclass(frozen=True)
class _Trial:
    """One reconstruction of the latent frames made with one set of sensor values."""

    label: str
    calibration: SensorCalibration
    folder: Path
    names: list[list[str]]
    split_us: np.ndarray
    outcome: Outcome

    @property
    def mean_track_length(self) -> float:
        """Mean number of registered latent frames that see each 3-D point."""
        model = self.outcome.model
        return sum(model.track_counts.values()) / max(len(model.points), 1)

    @property
    def quality(self) -> tuple:
        """What COLMAP says of it, the better the larger.

        A model that met the registration target, the share of latent frames registered (to
        1 %), longer tracks, then a smaller reprojection error.
        """
        total = sum(len(view) for view in self.names)
        return (
            self.outcome.succeeded,
            round(len(self.outcome.model.c2w) / max(total, 1), 2),
            round(self.mean_track_length, 1),
            -self.outcome.model.reprojection_error_px,
        )

    def colmap_says(self) -> dict:
        """The numbers the comparison was made on, for the report."""
        return {
            "registered": len(self.outcome.model.c2w),
            "mean_track_length": self.mean_track_length,
            "reprojection_error_px": self.outcome.model.reprojection_error_px,
            "threshold": self.calibration.threshold,
        }


def _labelled(progress: Progress, label: str) -> Progress:
    """``progress`` with each stage named for the sensor values its latent frames were made with."""

    def named(stage: str, done: int, total: int) -> None:
        progress(f"{stage} ({label} sensor)", done, total)

    return named


def _reconstruct(session, b, label, calibration, folder, lens, progress) -> _Trial:
    bins = contrast_bins(session, b, calibration)
    names, scores = _write_latent_frames(
        session, bins, calibrated_response(calibration), folder / "images", progress
    )
    total = len(names) * (b + 1)
    registered_so_far = [0]

    def on_image() -> None:
        registered_so_far[0] = min(registered_so_far[0] + 1, total)
        progress("registering", registered_so_far[0], total)

    outcome = reconstruct_with_recovery(
        folder,
        folder / "images",
        names,
        scores,
        lens=lens,
        stage=lambda name: progress(name, 0, 0),
        on_image=on_image,
    )
    return _Trial(label, calibration, folder, names, bins.split_us, outcome)


def _promote(folder: Path, work_dir: Path) -> None:
    """Make ``folder`` (inside ``work_dir``) the COLMAP work of the session, replacing the rest."""
    for entry in work_dir.iterdir():
        if entry != folder:
            shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
    for entry in folder.iterdir():
        entry.rename(work_dir / entry.name)
    folder.rmdir()
