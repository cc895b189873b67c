import itertools
import subprocess
import sys

import cv2
import numpy as np
import pycolmap
import pytest
from pose_scenes import HEIGHT, INTRINSICS, WIDTH, orbit_poses, render_box, texture

from davis_io.cores import cores_limited
from davis_io.geometry import align_poses, rotation_error_deg
from davis_io.lens import Lens
from davis_io.poses import recovery
from davis_io.poses.colmap import (
    LONG_RECORDING_GROWTH,
    ColmapError,
    Matcher,
    SparseModel,
    _pipeline_options,
    extract_features,
    match_features,
    sparse_model_from,
)
from davis_io.poses.recovery import reconstruct_with_recovery


def write_views(folder, poses, flat=False):
    folder.mkdir(parents=True)
    textures = [texture(seed) for seed in range(6)]
    names = []
    for i, c2w in enumerate(poses):
        names.append([f"{i:04d}_0.png"])
        image = render_box(c2w, textures, flat=flat)
        cv2.imwrite(str(folder / names[-1][0]), np.rint(image * 255).astype(np.uint8))
    return names


def test_box_views_reconstruct_at_their_known_poses(tmp_path):
    poses = orbit_poses(8)
    names = write_views(tmp_path / "images", poses)
    stages = []
    outcome = reconstruct_with_recovery(
        tmp_path / "colmap",
        tmp_path / "images",
        names,
        [[1.0]] * 8,
        lens=Lens.pinhole(WIDTH, HEIGHT, INTRINSICS),
        stage=stages.append,
    )
    assert outcome.strategy == "exhaustive" and outcome.succeeded
    assert stages[:2] == ["features", "matching (exhaustive)"]
    estimated = np.array([outcome.model.c2w[view[0]] for view in names])
    aligned = align_poses(estimated, poses).apply_poses(estimated)
    # Noise-free renders: sub-pixel features give poses within hundredths of a degree / mm.
    assert np.median(rotation_error_deg(aligned[:, :3, :3], poses[:, :3, :3])) < 0.1
    assert np.median(np.linalg.norm(aligned[:, :3, 3] - poses[:, :3, 3], axis=1)) < 0.005
    assert np.allclose(outcome.model.intrinsics, INTRINSICS)
    assert min(outcome.model.track_counts.values()) > 100
    # Every point lies inside the 4 m box, seen from under 1 m off centre: depth below 5 m.
    scale = align_poses(estimated, poses).scale
    assert 0 < outcome.model.bounds[0] < outcome.model.bounds[1] < 5.0 / scale


def test_features_extracted_on_two_threads_are_those_of_one_with_ids_in_names_order(
    tmp_path, monkeypatch
):
    names = [name for (name,) in write_views(tmp_path / "images", orbit_poses(6))][::-1]
    monkeypatch.setattr("os.sched_getaffinity", lambda _pid: {0, 1})
    found = {}
    for threads in (1, 2):
        with cores_limited(threads):
            database = extract_features(tmp_path / f"t{threads}", tmp_path / "images", names)
        with pycolmap.Database.open(database) as opened:
            images = sorted(opened.read_all_images(), key=lambda image: image.image_id)
            found[threads] = [
                (image.name, opened.read_keypoints(image.image_id).tobytes()) for image in images
            ]
    # Ids in the names' order (whatever the order given, here backwards), not in the order the
    # threads finish in; the same features.
    assert [name for name, _ in found[2]] == sorted(names)
    assert found[1] == found[2]


def test_textureless_views_give_a_colmap_error_with_advice(tmp_path):
    names = write_views(tmp_path / "images", orbit_poses(4), flat=True)
    with pytest.raises(ColmapError, match="texture") as error:
        reconstruct_with_recovery(tmp_path / "colmap", tmp_path / "images", names, [[1.0]] * 4)
    tried = "exhaustive, all-at-once, guided, relaxed-initialisation, sharpest-per-view"
    assert tried in str(error.value)


def test_sigterm_ends_a_process_that_imported_pycolmap_without_a_native_stack_dump():
    kill_self = (
        "import os, signal, time\n"
        "import davis_io.poses.colmap\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(5)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", kill_self], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == -15  # ended by the signal, as without pycolmap
    assert "stack trace" not in done.stderr and "Aborted" not in done.stderr


def test_a_verbs_sigterm_handler_survives_importing_pycolmap():
    # The verb installs its handler first (seecap's main does), then imports COLMAP's module.
    handled = (
        "import os, signal, sys, time\n"
        "signal.signal(signal.SIGTERM, lambda *_: (print('handled', flush=True), sys.exit(143)))\n"
        "import davis_io.poses.colmap\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(5)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", handled], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 143 and done.stdout == "handled\n"


@pytest.mark.parametrize(("focal", "plausible"), [(289.0, True), (34.0, False), (14813.0, False)])
def test_a_camera_outside_colmaps_own_bounds_is_not_plausible(focal, plausible):
    reconstruction = pycolmap.Reconstruction()
    reconstruction.add_camera(
        pycolmap.Camera(
            model="SIMPLE_PINHOLE", width=346, height=260, params=[focal, 173.0, 130.0], camera_id=1
        )
    )
    # 0.1 to 10 times the larger side, 346 px: 34.6 to 3460 px.
    assert sparse_model_from(reconstruction).plausible_camera is plausible


@pytest.mark.parametrize(
    ("fx", "fy", "plausible"), [(131.81, 131.70, True), (280.0, 290.0, True), (114.2, 54.06, False)]
)
def test_a_camera_whose_pixels_are_not_square_is_not_plausible(fx, fy, plausible):
    # A lens refined with two focal lengths (COLMAP's OPENCV): 1.0008 and 1.036 pass, 2.1 fails.
    reconstruction = pycolmap.Reconstruction()
    reconstruction.add_camera(
        pycolmap.Camera(
            model="OPENCV",
            width=173,
            height=130,
            params=[fx, fy, 86.0, 64.5, 0.12, 0.0, 0.15, -0.11],
            camera_id=1,
        )
    )
    assert sparse_model_from(reconstruction).plausible_camera is plausible


def test_a_short_recording_matches_every_pair_of_its_latent_frames():
    names = [[f"{view}_{latent}" for latent in range(5)] for view in range(12)]
    assert recovery.image_pairs(names, [[0.0] * 5] * 12) is None  # 1,770 pairs: every one
    assert recovery.matched_pair_count(12, 5) == 1770
    # 13 views: 2,080 pairs, beyond the limit: 78 keyframe pairs, 130 within views, 300 one
    # view apart and 275 two apart, less the 23 keyframe pairs counted twice.
    assert recovery.matched_pair_count(13, 5) == 760


def test_a_long_recording_matches_keyframes_with_each_other_and_latent_frames_with_nearby_views(
    monkeypatch,
):
    monkeypatch.setattr(recovery, "EVERY_PAIR_LIMIT", 0)
    names = [[f"{view}_{latent}" for latent in range(2)] for view in range(4)]
    sharpness = [[0.0, 1.0]] * 4  # keyframes: the second latent frame of each view
    pairs = recovery.image_pairs(names, sharpness)
    # Of the 28 pairs of 8 images, the three between views 0 and 3 that are not both keyframes
    # are left out (two views apart at most): 6 keyframe pairs, 4 within views, 12 one view
    # apart, 8 two apart, less the 5 keyframe pairs counted twice.
    assert recovery.NEIGHBOUR_VIEWS == 2 and len(pairs) == 25 == len(set(pairs))
    left_out = {("0_0", "3_0"), ("0_0", "3_1"), ("0_1", "3_0")}
    every = {tuple(sorted(pair)) for pair in itertools.combinations(sum(names, []), 2)}
    assert every - set(pairs) == left_out and ("0_1", "3_1") in pairs
    assert recovery.matched_pair_count(4, 2) == 25
    for views, per_view in [(1, 5), (2, 3), (3, 4), (30, 5), (7, 1)]:
        names = [[f"{view}_{latent}" for latent in range(per_view)] for view in range(views)]
        pairs = recovery.image_pairs(names, [[1.0] * per_view] * views)
        assert recovery.matched_pair_count(views, per_view) == len(pairs)


def test_a_long_recording_is_mapped_with_fewer_global_adjustments(tmp_path, monkeypatch):
    mapped = []
    monkeypatch.setattr(recovery, "reconstruct", lambda *args, **_kw: mapped.append(args[3]))
    names = [[f"{view}_{latent}.png" for latent in range(3)] for view in range(4)]
    sharpness = [[0.0, 1.0, 0.0]] * 4
    keyframes_first = recovery.STRATEGIES[0]
    assert keyframes_first.order is recovery.Order.KEYFRAMES_FIRST
    every = [name for view in names for name in view]
    recovery._map(keyframes_first, every, tmp_path, tmp_path, names, sharpness, {})
    monkeypatch.setattr(recovery, "EVERY_PAIR_LIMIT", 65)  # 12 images: 66 pairs
    recovery._map(keyframes_first, every, tmp_path, tmp_path, names, sharpness, {})
    keyframes = tuple(view[1] for view in names)
    assert [settings.image_names for settings in mapped] == [keyframes, tuple(every)] * 2
    assert [settings.long_recording for settings in mapped] == [False, False, True, True]
    short, long = (_pipeline_options(mapped[i], fixed_intrinsics=False) for i in (1, 3))
    assert (short.ba_global_frames_ratio, short.ba_global_points_ratio) == (1.1, 1.1)  # COLMAP's
    assert not short.mapper.ba_global_ignore_redundant_points3D
    assert long.ba_global_frames_ratio == long.ba_global_points_ratio == LONG_RECORDING_GROWTH
    assert long.mapper.ba_global_ignore_redundant_points3D and LONG_RECORDING_GROWTH > 1.1


def test_only_the_chosen_pairs_are_matched(tmp_path):
    names = [name for (name,) in write_views(tmp_path / "images", orbit_poses(5))]
    database = extract_features(tmp_path / "colmap", tmp_path / "images", names)
    chosen = [(names[0], names[1]), (names[0], names[4]), (names[2], names[3])]
    match_features(database, Matcher.EXHAUSTIVE, chosen)
    with pycolmap.Database.open(database) as opened:
        ids = {image.name: image.image_id for image in opened.read_all_images()}
        assert opened.num_matched_image_pairs() == 3  # of the 10 pairs of 5 views
        assert all(opened.exists_matches(ids[a], ids[b]) for a, b in chosen)
        assert not opened.exists_matches(ids[names[0]], ids[names[2]])
    match_features(database, Matcher.EXHAUSTIVE)  # every pair, the earlier ones replaced
    with pycolmap.Database.open(database) as opened:
        assert opened.num_matched_image_pairs() == 10


def test_recovery_passes_over_a_model_with_an_implausible_camera(tmp_path, monkeypatch):
    names = [[f"{view}_{latent}.png" for latent in range(2)] for view in range(4)]
    every = [name for view in names for name in view]

    def mapped(strategy, images, *_args):
        degenerate = strategy.name == "exhaustive"  # everything registered, at 40x the width
        return SparseModel(
            c2w={name: np.eye(4) for name in images},
            intrinsics=np.array([14813.0, 14813.0, 172.5, 129.5]) if degenerate else INTRINSICS,
            distortion=np.zeros(0),
            points=np.zeros((0, 3)),
            plausible_camera=not degenerate,
        )

    monkeypatch.setattr(recovery, "extract_features", lambda *_args, **_kw: tmp_path / "db")
    monkeypatch.setattr(recovery, "match_features", lambda *_args: None)
    monkeypatch.setattr(recovery, "_map", mapped)
    outcome = reconstruct_with_recovery(tmp_path, tmp_path, names, [[0.0, 1.0]] * 4)
    assert (outcome.strategy, outcome.tried) == ("all-at-once", ("exhaustive", "all-at-once"))
    assert sorted(outcome.model.c2w) == sorted(every)


def test_an_unknown_pinhole_is_estimated_as_one(tmp_path, capfd):
    poses = orbit_poses(8)
    names = write_views(tmp_path / "images", poses)
    stages = []
    outcome = reconstruct_with_recovery(
        tmp_path / "colmap", tmp_path / "images", names, [[1.0]] * 8, stage=stages.append
    )
    assert stages[-1] == "lens"
    model = outcome.model
    # The radial lens fitted after mapping finds no distortion in pinhole renders (or is not
    # kept), and the focal length the mapping estimated stays within half a percent.
    assert np.all(np.abs(model.distortion) < 0.01)
    assert model.intrinsics[0] == pytest.approx(INTRINSICS[0], rel=5e-3)
    assert (model.folder / "cameras.bin").is_file()
    printed = capfd.readouterr()
    assert "bundle adjustment" not in printed.out + printed.err  # COLMAP's log stays quiet


@pytest.mark.parametrize("second_registers", [8, 6])
def test_an_estimated_lens_that_bends_the_corners_is_mapped_with_again(
    tmp_path, monkeypatch, second_registers
):
    names = [[f"{view}_{latent}.png" for latent in range(2)] for view in range(4)]
    every = [name for view in names for name in view]
    calls = []

    def model(count, distortion=(), folder=None):
        return SparseModel(
            c2w={name: np.eye(4) for name in every[:count]},
            intrinsics=np.array([300.0, 300.0, 172.5, 129.5]),
            distortion=np.asarray(distortion, float),
            points=np.zeros((0, 3)),
            folder=folder,
            image_size=(346, 260),
        )

    def mapped(strategy, images, work_dir, image_dir, names, sharpness, mapping, folder=""):
        calls.append((folder, mapping["fixed_intrinsics"]))
        return model(8) if not folder else model(second_registers, (-0.2, 0.03), tmp_path)

    monkeypatch.setattr(recovery, "extract_features", lambda *_args, **_kw: tmp_path / "db")
    monkeypatch.setattr(recovery, "match_features", lambda *_args: None)
    monkeypatch.setattr(recovery, "_map", mapped)
    monkeypatch.setattr(recovery, "with_radial_lens", lambda m: model(8, (-0.15,)))
    given = []
    monkeypatch.setattr(recovery, "use_lens", lambda _database, lens: given.append(lens))
    outcome = reconstruct_with_recovery(tmp_path, tmp_path, names, [[0.0, 1.0]] * 4)
    # k1 -0.15 moves the corners of a 346 x 260 image at f 300 by about 12 px: mapped again,
    # starting from the estimate, its values refined.
    assert given[0].distortion == (-0.15,) and given[0].corner_shift_px() > 10
    assert calls == [("", False), ("exhaustive-lens", False)]
    kept = outcome.model.distortion.tolist()
    assert kept == ([-0.2, 0.03] if second_registers == 8 else [-0.15])  # fewer registered: not
