"""The one module that talks to COLMAP (through pycolmap, never a subprocess).

Feature extraction into one database, matching, and incremental mapping into one sparse model
per attempt, all kept in a working folder (``session/colmap/``) so a later run reuses them.

The same frames give the same poses bit for bit. Feature extraction runs on every core, the
images given their ids in order before it; matching and mapping run on one thread: on more,
matches and bundle adjustment follow the threads' timing.
"""

from __future__ import annotations

import dataclasses
import enum
import shutil
import signal
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from davis_io.cores import usable_cores
from davis_io.errors import DavisIOError
from davis_io.geometry import (
    c2w_from_w2c,
    colmap_from_opencv_intrinsics,
    opencv_from_colmap_intrinsics,
)
from davis_io.lens import Lens

__all__ = [
    "DATABASE_NAME",
    "ColmapError",
    "LONG_RECORDING_GROWTH",
    "MAX_PIXEL_ASPECT",
    "MapperSettings",
    "Matcher",
    "SparseModel",
    "extract_features",
    "match_features",
    "reconstruct",
]

DATABASE_NAME = "database.db"
PAIRS_NAME = "pairs.txt"
SEED = 0


def _import_pycolmap():
    """pycolmap, imported without losing the SIGTERM handler in place before it.

    pycolmap installs glog's failure handler for SIGTERM when imported: a plain ``kill`` then
    printed the native stack of a process that did nothing wrong, and the verb's own handler
    (its one line and exit 143) was gone. The handler before the import is put back.
    """
    before = signal.getsignal(signal.SIGTERM)
    import pycolmap

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, signal.SIG_DFL if before is None else before)
    return pycolmap


pycolmap = _import_pycolmap()


class ColmapError(DavisIOError):
    """COLMAP could not reconstruct the images (too little texture, overlap or parallax)."""


class Matcher(enum.Enum):
    """How image pairs get matched (every pair of images is matched)."""

    EXHAUSTIVE = "exhaustive"
    """SIFT nearest neighbours with the ratio test and cross check, then RANSAC verification."""
    GUIDED = "guided"
    """A looser ratio test, then matches guided by the verified two-view geometry (more
    matches on weak texture and blur)."""


@dataclass(frozen=True)
class MapperSettings:
    """Incremental mapping settings that the recovery strategies vary.

    Attributes:
        relaxed_initialisation: accept an initial pair with fewer inliers and a smaller
            triangulation angle (2 degrees instead of 4; COLMAP's own default is 16) and
            register images with fewer inliers.
        image_names: map only these images (all images in the database when empty).
        long_recording: adjust the whole model less often and over fewer points
            (:data:`LONG_RECORDING_GROWTH`).
    """

    relaxed_initialisation: bool = False
    image_names: tuple[str, ...] = ()
    long_recording: bool = False


@dataclass(frozen=True)
class SparseModel:
    """What a reconstruction gives back, in plain arrays.

    Attributes:
        c2w: camera-to-world ``4x4`` (OpenCV axes, COLMAP units) per registered image name.
        intrinsics: ``(fx, fy, cx, cy)`` of the shared camera, pixels, session convention
            (pixel centres at integers).
        distortion: the camera's remaining parameters (radial terms), empty for pinhole.
        points: ``(N, 3)`` sparse 3-D points.
        track_counts: number of 3-D points each registered image observes.
        bounds: ``(near, far)`` depth of the sparse points seen by the registered images
            (1st and 99th percentiles of all observations, trimming stray points), COLMAP units.
        reprojection_error_px: mean reprojection error of all observations, pixels.
        plausible_camera: whether the camera passes COLMAP's own sanity bounds (focal length
            0.1 to 10 times the larger image side, small distortion terms) and has square
            pixels (:data:`MAX_PIXEL_ASPECT`); a degenerate model of a few images can drift far
            outside them.
        folder: where COLMAP's files of the model are (None: not written).
        image_size: ``(width, height)`` of the camera's images (0, 0: unknown).
    """

    c2w: dict[str, np.ndarray]
    intrinsics: np.ndarray
    distortion: np.ndarray
    points: np.ndarray
    track_counts: dict[str, int] = field(default_factory=dict)
    bounds: np.ndarray = field(default_factory=lambda: np.zeros(2))
    reprojection_error_px: float = 0.0
    plausible_camera: bool = True
    folder: Path | None = None
    image_size: tuple[int, int] = (0, 0)

    @property
    def lens(self) -> Lens:
        """The camera's lens: its intrinsics and distortion."""
        return Lens.pinhole(*self.image_size, self.intrinsics).with_distortion(self.distortion)


def _quiet() -> None:
    pycolmap.logging.minloglevel = 3  # failures come back as ColmapError with advice instead
    pycolmap.set_random_seed(SEED)


def extract_features(
    work_dir: Path,
    image_dir: Path,
    image_names: Sequence[str],
    *,
    lens: Lens | None = None,
) -> Path:
    """Write SIFT features of ``image_names`` (one shared camera) to ``work_dir/database.db``.

    Args:
        work_dir: folder that keeps the database (created).
        image_dir: folder holding the images.
        image_names: file names inside ``image_dir``, in capture order.
        lens: the camera's known lens (COLMAP's ``PINHOLE``, ``OPENCV`` or ``FULL_OPENCV``
            model with its values, held fixed), or ``None`` to let COLMAP estimate one focal
            length (principal point at the centre, no distortion).

    Returns:
        The database path. An existing database is replaced.
    """
    _quiet()
    work_dir.mkdir(parents=True, exist_ok=True)
    database = work_dir / DATABASE_NAME
    database.unlink(missing_ok=True)
    reader = pycolmap.ImageReaderOptions()
    # One focal length and no distortion while unknown: a radial term with the focal length
    # collapses on the small baselines of a hand-held sweep.
    reader.camera_model = "SIMPLE_PINHOLE"
    if lens is not None:
        reader.camera_model, values = colmap_camera(lens)
        reader.camera_params = ",".join(f"{value:.9g}" for value in values)
    # The images get their ids in order here, before threads extract their features (which
    # would give ids as they finish): 80 latent frames, the same database in 12.4 s on one
    # thread and in 6.5 s on two.
    pycolmap.Database.open(database).close()
    pycolmap.import_images(
        database,
        image_dir,
        camera_mode=pycolmap.CameraMode.SINGLE,
        image_names=list(image_names),
        options=reader,
    )
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.use_gpu = False
    extraction.num_threads = usable_cores()
    pycolmap.extract_features(
        database,
        image_dir,
        image_names=list(image_names),
        camera_mode=pycolmap.CameraMode.SINGLE,
        reader_options=reader,
        extraction_options=extraction,
        device=pycolmap.Device.cpu,
    )
    return database


def colmap_camera(lens: Lens) -> tuple[str, list[float]]:
    """COLMAP's camera model and parameters of ``lens`` (pixel centres moved to +0.5)."""
    values = list(colmap_from_opencv_intrinsics(lens.intrinsics))
    if lens.is_pinhole:
        return "PINHOLE", values
    coefficients = list(lens.coefficients)
    if len(coefficients) == 4:
        return "OPENCV", values + coefficients
    return "FULL_OPENCV", values + coefficients + [0.0] * (8 - len(coefficients))


def match_features(
    database: Path, matcher: Matcher, pairs: Sequence[tuple[str, str]] | None = None
) -> None:
    """Match and geometrically verify image pairs, replacing earlier matches.

    Args:
        database: database written by :func:`extract_features`.
        matcher: how to match.
        pairs: the image pairs to match, by name (every pair when None).
    """
    _quiet()
    with pycolmap.Database.open(database) as opened:
        opened.clear_matches()
        opened.clear_two_view_geometries()
    matching = pycolmap.FeatureMatchingOptions()
    matching.use_gpu = False
    # One thread: on two, the same features gave other matches on some runs (3,160 pairs in
    # 26 s instead of 34; two runs in four differed).
    matching.num_threads = 1
    if matcher is Matcher.GUIDED:
        matching.guided_matching = True
        matching.sift.max_ratio = 0.9
    if pairs is None:
        pycolmap.match_exhaustive(database, matching_options=matching, device=pycolmap.Device.cpu)
        return
    pair_list = database.with_name(PAIRS_NAME)
    pair_list.write_text("".join(f"{first} {second}\n" for first, second in pairs))
    pycolmap.match_image_pairs(
        database,
        matching_options=matching,
        pairing_options=pycolmap.ImportedPairingOptions(match_list_path=pair_list),
        device=pycolmap.Device.cpu,
    )


LONG_RECORDING_GROWTH = 1.25
"""A long recording's model is adjusted as a whole each time it grows by this factor (COLMAP's
1.1), over the 3-D points that add to the images' coverage only. The global adjustments over
hundreds of latent frames are what made its mapping grow faster than its frames. Keyframes then
every latent frame, pinhole, one thread, errors against the truth after a similarity alignment
(rotation median / max, centres median / max of the scene's extent):

* room, 100 views at b = 4 (500 latent frames): 535 s instead of 1,136 s; 0.183 / 0.467
  degrees instead of 0.170 / 0.449; centres 0.44 % / 1.39 % either way;
* room, 40 views: 86 s instead of 102 s; 0.139 / 0.329 degrees instead of 0.145 / 0.359;
  centres 0.64 % / 1.9 % instead of 0.63 % / 2.1 %.

Leaving out the redundant points alone gave 855 s on the 100 views (0.176 / 0.449 degrees).

Tried on every recording, it maps 80 latent frames in 17-19 s instead of 23-28 s (room, lamp) at
errors within the spread that other random draws of the verification give. But small recordings
lost accuracy beyond that spread: four frames 0.219 degrees median against 0.119-0.168; ten
frames, six of them held still, through a random distorted lens 0.089 against 0.035-0.044. So
only long recordings use it."""


def _pipeline_options(settings: MapperSettings, fixed_intrinsics: bool):
    options = pycolmap.IncrementalPipelineOptions()
    # A first initial pair can settle on a degenerate model (three keyframes at a focal length
    # 40x the image width, nothing more registers); further models from other pairs find the
    # scene, and the largest one is kept.
    options.multiple_models = True
    options.random_seed = SEED
    options.num_threads = 1  # parallel bundle adjustment sums in another order every run
    options.extract_colors = False
    options.image_names = list(settings.image_names)
    options.mapper.init_min_tri_angle = 4.0  # COLMAP's 16 degrees rejects handheld baselines
    if fixed_intrinsics:
        options.ba_refine_focal_length = False
        options.ba_refine_extra_params = False
        options.ba_refine_principal_point = False
    if settings.long_recording:
        options.ba_global_frames_ratio = LONG_RECORDING_GROWTH
        options.ba_global_points_ratio = LONG_RECORDING_GROWTH
        options.mapper.ba_global_ignore_redundant_points3D = True
    if settings.relaxed_initialisation:
        options.mapper.init_min_tri_angle = 2.0
        options.mapper.init_min_num_inliers = 50
        options.mapper.abs_pose_min_num_inliers = 15
        options.mapper.init_max_forward_motion = 0.99
        options.min_model_size = 3
    return options


def reconstruct(
    database: Path,
    image_dir: Path,
    model_dir: Path,
    settings: MapperSettings = MapperSettings(),
    *,
    fixed_intrinsics: bool = False,
    start_from: Path | None = None,
    on_image: Callable[[], None] | None = None,
) -> SparseModel:
    """Incremental mapping of the database's images into ``model_dir`` (replaced if present).

    Args:
        database: database with features and verified matches.
        image_dir: folder holding the images.
        model_dir: folder for the sparse model (COLMAP binary files).
        settings: initialisation and image subset.
        fixed_intrinsics: keep the database camera's parameters (known intrinsics).
        start_from: a model folder to extend (its images keep their registration).
        on_image: called each time an image is registered (progress display).

    Returns:
        The largest model found.

    Raises:
        ColmapError: no model could be built.
    """
    _quiet()
    shutil.rmtree(model_dir, ignore_errors=True)
    model_dir.mkdir(parents=True)
    models = pycolmap.incremental_mapping(
        database,
        image_dir,
        model_dir,
        options=_pipeline_options(settings, fixed_intrinsics),
        input_path=start_from or "",
        next_image_callback=on_image,
    )
    if not models:
        raise ColmapError(
            "COLMAP found no initial image pair with enough matches: the frames have too little "
            "texture or overlap. Record a scene with more visible detail, move the camera more "
            "slowly or use more frames"
        )
    best = max(models.values(), key=lambda model: (_plausible(model), model.num_reg_images()))
    best.write(model_dir)
    return dataclasses.replace(sparse_model_from(best), folder=model_dir)


RADIAL_LENS = "RADIAL"
"""COLMAP's model of an unknown lens, fitted once the mapping with a pinhole is done: a focal
length and two radial terms (the principal point stays at the centre)."""

RADIAL_FUNCTION_TOLERANCE = 1e-8
"""The radial lens's adjustment ends once a step lowers the error by less than this share of it.
COLMAP's 0 runs all 100 iterations: 500 latent frames (room, 100 views at b = 4) took 203 s
instead of 54 s for the same lens (focal length 282.49 px, k1 0.0025, k2 -0.0202) and the same
poses (0.143 / 0.404 degrees of rotation error, median / max). The default room's 80 gave the
same lens and poses either way, in 4-5 s. At 1e-6 the long recording took 40 s, but its focal
length moved 0.28 px further from the truth's 280 px."""

MAX_PIXEL_ASPECT = 1.05
"""Largest ratio of an estimated camera's two focal lengths. A DAVIS's pixels are square (18.5 µm
on the DAVIS346), so the two agree to a fraction of a percent when the lens is measured; refining
a lens on noisy latent frames (an emulated pixel with 10 times the noisy preset's noise) once gave
114 and 54 px, a camera no DAVIS has."""

RADIAL_NO_WORSE = 1.01
"""Largest ratio of the radial model's mean reprojection error to the pinhole's it is kept at."""


def with_radial_lens(model: SparseModel) -> SparseModel:
    """The model bundle-adjusted again with a radial lens, or ``model`` when that does not serve.

    Mapping starts from a pinhole: a radial term estimated with the focal length from the first
    pair collapses on the short baselines of a hand-held sweep. From the finished model, a
    radial lens lowers the error a pinhole leaves, but its focal length stays near the one the
    pinhole inflated to take up the distortion (the error barely changes along focal length
    and radial terms together); a second mapping from this lens finds both
    (:func:`davis_io.poses.recovery.reconstruct_with_recovery`). The radial model is kept
    (written over the model's folder) when its camera is plausible and its reprojection error
    is no worse.
    """
    if model.folder is None or model.distortion.size:
        return model
    _quiet()
    reconstruction = pycolmap.Reconstruction(str(model.folder))
    camera = next(iter(reconstruction.cameras.values()))
    focal, cx, cy = (float(v) for v in camera.params[:3])
    camera.model = getattr(pycolmap.CameraModelId, RADIAL_LENS)
    camera.params = [focal, cx, cy, 0.0, 0.0]
    reconstruction.cameras[camera.camera_id] = camera
    options = pycolmap.BundleAdjustmentOptions()
    options.refine_focal_length = True
    options.refine_extra_params = True
    options.refine_principal_point = False
    options.print_summary = False
    options.ceres.solver_options.num_threads = 1  # in parallel it sums in another order each run
    options.ceres.solver_options.function_tolerance = RADIAL_FUNCTION_TOLERANCE
    problem = pycolmap.BundleAdjustmentConfig()
    for image_id, image in reconstruction.images.items():
        if image.has_pose:
            problem.add_image(image_id)
    problem.fix_gauge(pycolmap.BundleAdjustmentGauge.TWO_CAMS_FROM_WORLD)
    # The adjuster itself, not pycolmap.bundle_adjustment: that one logs to the terminal.
    pycolmap.create_default_bundle_adjuster(options, problem, reconstruction).solve()
    reconstruction.update_point_3d_errors()
    error = reconstruction.compute_mean_reprojection_error()
    if not (_plausible(reconstruction) and error <= RADIAL_NO_WORSE * model.reprojection_error_px):
        return model
    reconstruction.write(model.folder)
    return dataclasses.replace(sparse_model_from(reconstruction), folder=model.folder)


def use_lens(database: Path, lens: Lens) -> None:
    """Give the database's camera ``lens`` as its starting values for the next mapping."""
    model, values = colmap_camera(lens)
    with pycolmap.Database.open(database) as opened:
        for camera in opened.read_all_cameras():
            camera.model = getattr(pycolmap.CameraModelId, model)
            camera.params = values
            opened.update_camera(camera)


def model_points(model_dir: Path) -> np.ndarray:
    """``(N, 3)`` 3-D points of the sparse model written in ``model_dir``."""
    reconstruction = pycolmap.Reconstruction(str(model_dir))
    return np.array([point.xyz for point in reconstruction.points3D.values()]).reshape(-1, 3)


def sparse_model_from(reconstruction: pycolmap.Reconstruction) -> SparseModel:
    """Plain arrays from a pycolmap reconstruction with one shared camera."""
    camera = next(iter(reconstruction.cameras.values()))
    focal = camera.focal_length_idxs()
    params = np.asarray(camera.params, float)
    fx, fy = params[focal[0]], params[focal[-1]]
    cx, cy = camera.principal_point_x, camera.principal_point_y
    extra = np.asarray([params[i] for i in camera.extra_params_idxs()], float)
    c2w, tracks, depths = {}, {}, []
    points = {pid: p.xyz for pid, p in reconstruction.points3D.items()}
    for image in reconstruction.images.values():
        if not image.has_pose:
            continue
        pose = image.cam_from_world().matrix()
        c2w[image.name] = c2w_from_w2c(pose[:, :3], pose[:, 3])
        seen = [p.point3D_id for p in image.points2D if p.has_point3D()]
        tracks[image.name] = len(seen)
        if seen:
            xyz = np.array([points[pid] for pid in seen])
            depths.append(xyz @ pose[2, :3] + pose[2, 3])
    depths = np.concatenate(depths) if depths else np.zeros(0)
    bounds = np.percentile(depths, [1.0, 99.0]) if depths.size else np.zeros(2)
    return SparseModel(
        c2w=c2w,
        intrinsics=opencv_from_colmap_intrinsics([fx, fy, cx, cy]),
        distortion=extra,
        points=np.array(list(points.values())).reshape(-1, 3),
        track_counts=tracks,
        bounds=bounds,
        reprojection_error_px=float(reconstruction.compute_mean_reprojection_error()),
        plausible_camera=_plausible(reconstruction),
        image_size=(int(camera.width), int(camera.height)),
    )


def _plausible(reconstruction: pycolmap.Reconstruction) -> bool:
    """Whether every camera lies within the mapper's own limits of a sane camera, square pixels."""
    sane = pycolmap.IncrementalMapperOptions()
    return not any(
        camera.has_bogus_params(
            sane.min_focal_length_ratio, sane.max_focal_length_ratio, sane.max_extra_param
        )
        or _pixel_aspect(camera) > MAX_PIXEL_ASPECT
        for camera in reconstruction.cameras.values()
    )


def _pixel_aspect(camera: pycolmap.Camera) -> float:
    """The larger of the camera's two focal lengths over the smaller (1 for one focal length)."""
    focal = [float(camera.params[i]) for i in camera.focal_length_idxs()]
    return max(focal) / min(focal) if min(focal) > 0 else float("inf")
