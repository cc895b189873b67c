"""Reconstruction with fallbacks: the documented strategies, tried in order until one registers.

Most strategies map the sharpest latent frame of each view first (wider baselines for the
initial pair) and then register all latent frames into that model.

1. ``exhaustive``: SIFT matching of every pair (the default). A long recording matches only the
   pairs a camera path can share (:func:`image_pairs`): every pair's cost grows with the square
   of the frames.
2. ``all-at-once``: the same matches, every latent frame mapped from the start. A handful of
   keyframes can settle on a degenerate model: six views of a small room session registered 4
   of their 30 latent frames at a focal length of 2094 px (true 140) after every keyframe-first
   strategy, and all 30 at 154 px mapped at once.
3. ``guided``: another matcher, a looser ratio test plus geometry-guided matching.
4. ``relaxed-initialisation``: accept a smaller, lower-parallax initial pair.
5. ``sharpest-per-view``: map only the sharpest latent frame of each view; the other latent
   time points get poses interpolated in time (done by the caller for every unregistered one).

A strategy succeeds when it registers at least ``REGISTERED_FRACTION`` of its images. A model
whose estimated camera is not plausible (COLMAP's own bounds: a focal length 0.1 to 10 times the
larger image side) counts as no model at all: a degenerate one can register a few images at any
focal length, and was once kept at 12 times the image width.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np

from davis_io.lens import Lens
from davis_io.poses.colmap import (
    DATABASE_NAME,
    ColmapError,
    MapperSettings,
    Matcher,
    SparseModel,
    extract_features,
    match_features,
    reconstruct,
    use_lens,
    with_radial_lens,
)

__all__ = [
    "EVERY_PAIR_LIMIT",
    "MINIMUM_FRACTION",
    "NEIGHBOUR_VIEWS",
    "REGISTERED_FRACTION",
    "STRATEGIES",
    "Outcome",
    "Strategy",
    "image_pairs",
    "is_long",
    "matched_pair_count",
    "reconstruct_with_recovery",
]

REGISTERED_FRACTION = 0.9
"""Share of a strategy's images that must register for it to count as a success."""

MINIMUM_FRACTION = 0.5
"""Below this share of its images (or under 3 images) even the best model is not usable."""

EVERY_PAIR_LIMIT = 2000
"""Every pair of latent frames is matched up to this many pairs (63 latent frames: 12 views
at b = 4), the neighbouring views' (:func:`image_pairs`) beyond, mapped with fewer global
adjustments (:data:`~davis_io.poses.colmap.LONG_RECORDING_GROWTH`). Every pair costs
0.012-0.015 s on one thread, their count grows with the square of the views.

Measured at 16 views, b = 4 (80 latent frames, 3,160 pairs of which the neighbouring views' are
976), every pair against the neighbours', whole pose step, rotation error median / max against
the truth (degrees), then fits of 1,500 steps on one thread from each (HDR / novel exposure
PSNR, dB):

* room: 86 s against 59 s; the fits 30.28 and 30.24 (two sets of the verification's random
  draws) against 30.24 HDR. An earlier measurement on four scenes had put the neighbours' fit of
  room 0.3 dB under and their rotation medians 0.005-0.024 over;
* five of the blind benchmark's sessions: 76-126 s against 33-59 s. Rotation medians rose on
  four of the five (+0.003 to +0.019; corridor-s16 -0.006); other random draws of the
  verification moved room's and lamp's by 0.006 and 0.010. The fits: room-s10 29.84 / 27.57
  against 29.82 / 27.66, room-s22 31.25 / 29.78 against 30.81 / 29.44, lamp-s5 32.28 / 24.49
  against 32.19 / 24.49, lamp-s9 31.69 / 26.39 against 31.46 / 26.24, corridor-s16 26.80 / 25.04
  against 27.65 / 25.46: on average +0.01 dB HDR and 0.00 novel, for half the time.

On the benchmark's scenes (whole pose step, calibrated before): room 41 s, 0.110 degrees,
against 109 s, 0.086 from every pair; lamp-film 47 s, 0.118, against 95 s, 0.100. Matched to
four views on either side instead of two, room-s22's rotation median was 0.147 (0.136 at two,
0.120 from every pair). Each latent frame matched with every view's keyframe as well (1,704
pairs) won the accuracy back (room 0.084, lamp-film 0.108) but took 68-75 s, over the minute the
step is given. At 40 views (room) the neighbouring views' 3,028 pairs of 19,900 took 243 s
instead of 544 s, 0.114 / 0.279 degrees instead of 0.088 / 0.255, centres 0.63 % / 2.1 % of the
scene's extent either way."""

NEIGHBOUR_VIEWS = 2
"""A long recording matches each latent frame with those of this many views on either side."""


class Order(Enum):
    """Which latent frames a strategy maps, and in which order."""

    KEYFRAMES_FIRST = "keyframes-first"
    """The sharpest latent frame of each view, then every latent frame into their model."""
    ALL_AT_ONCE = "all-at-once"
    """Every latent frame from the start."""
    KEYFRAMES_ONLY = "keyframes-only"
    """The sharpest latent frame of each view alone."""


@dataclass(frozen=True)
class Strategy:
    """One way of running COLMAP.

    Attributes:
        name: name shown in the report.
        matcher: how to match (a new matcher replaces the database's matches).
        relaxed_initialisation: see :class:`~davis_io.poses.colmap.MapperSettings`.
        order: which images are mapped, and in which order.
    """

    name: str
    matcher: Matcher
    relaxed_initialisation: bool = False
    order: Order = Order.KEYFRAMES_FIRST


REMAP_SHIFT_PX = 3.0
"""An estimated lens that moves the image's corners by more than this many pixels from a
pinhole's is mapped with again: the first mapping's focal length took up part of the distortion.
Measured: an undistorted emulated lens is estimated at 1.2 px, drawn lenses at 24-43 px before
the second mapping, a DAVIS346 lens as DV calibrates it moves them 66 px."""

STRATEGIES: tuple[Strategy, ...] = (
    Strategy("exhaustive", Matcher.EXHAUSTIVE),
    Strategy("all-at-once", Matcher.EXHAUSTIVE, order=Order.ALL_AT_ONCE),
    Strategy("guided", Matcher.GUIDED),
    Strategy("relaxed-initialisation", Matcher.GUIDED, relaxed_initialisation=True),
    Strategy(
        "sharpest-per-view", Matcher.GUIDED, relaxed_initialisation=True, order=Order.KEYFRAMES_ONLY
    ),
)


@dataclass(frozen=True)
class Outcome:
    """The model kept and how it was obtained.

    Attributes:
        model: the best sparse model found.
        strategy: name of the strategy that produced it.
        succeeded: whether that strategy reached ``REGISTERED_FRACTION``.
        tried: names of the strategies run, in order.
    """

    model: SparseModel
    strategy: str
    succeeded: bool
    tried: tuple[str, ...]


def _keyframes(names: Sequence[Sequence[str]], sharpness) -> list[str]:
    return [view[int(np.argmax(scores))] for view, scores in zip(names, sharpness, strict=True)]


def _pairs_among(images: int) -> int:
    return images * (images - 1) // 2


def _every_pair(images: int) -> bool:
    """Whether every pair of ``images`` latent frames is matched."""
    return _pairs_among(images) <= EVERY_PAIR_LIMIT


def is_long(names: Sequence[Sequence[str]]) -> bool:
    """Whether these views' latent frames are too many to match every pair of them.

    A long recording matches only nearby views (:func:`image_pairs`) and maps with fewer global
    adjustments (:attr:`~davis_io.poses.colmap.MapperSettings.long_recording`).
    """
    return not _every_pair(sum(len(view) for view in names))


def matched_pair_count(views: int, per_view: int) -> int:
    """The count of :func:`image_pairs` for ``views`` views of ``per_view`` latent frames each."""
    if _every_pair(views * per_view):
        return _pairs_among(views * per_view)
    reach = range(1, min(NEIGHBOUR_VIEWS, views - 1) + 1)
    near_keyframe_pairs = sum(views - step for step in reach)
    near = sum((views - step) * per_view**2 for step in reach) - near_keyframe_pairs
    return _pairs_among(views) + views * _pairs_among(per_view) + near


def image_pairs(names: Sequence[Sequence[str]], sharpness) -> list[tuple[str, str]] | None:
    """The pairs of latent frames to match; None for every pair (up to :data:`EVERY_PAIR_LIMIT`).

    Beyond it: the keyframes with each other (views far apart in time that see the same part of
    the scene), and each latent frame with those of its own view and of the
    :data:`NEIGHBOUR_VIEWS` views on either side.
    """
    if not is_long(names):
        return None
    pairs = set(itertools.combinations(_keyframes(names, sharpness), 2))
    for view, own in enumerate(names):
        for near in names[view : view + NEIGHBOUR_VIEWS + 1]:
            pairs.update((first, second) for first in own for second in near if first != second)
    return sorted({tuple(sorted(pair)) for pair in pairs})


def _images_of(strategy: Strategy, names: Sequence[Sequence[str]], sharpness) -> list[str]:
    if strategy.order is Order.KEYFRAMES_ONLY:
        return _keyframes(names, sharpness)
    return [name for view in names for name in view]


def _map(
    strategy, images, work_dir, image_dir, names, sharpness, mapping, folder: str = ""
) -> SparseModel:
    """Every image at once, the keyframes (sharpest per view) alone, or keyframes then all.

    The model goes to ``work_dir/sparse/<folder or the strategy's name>``.
    """
    model_dir = work_dir / "sparse" / (folder or strategy.name)

    def settings(mapped: Sequence[str]) -> MapperSettings:
        return MapperSettings(strategy.relaxed_initialisation, tuple(mapped), is_long(names))

    if strategy.order is not Order.KEYFRAMES_FIRST:  # its images are the ones to map
        return reconstruct(
            work_dir / DATABASE_NAME, image_dir, model_dir, settings(images), **mapping
        )
    keyframe_dir = model_dir / "keyframes"
    keyframes = settings(_keyframes(names, sharpness))
    reconstruct(work_dir / DATABASE_NAME, image_dir, keyframe_dir, keyframes, **mapping)
    return reconstruct(
        work_dir / DATABASE_NAME,
        image_dir,
        model_dir / "all",
        settings(images),
        start_from=keyframe_dir,
        **mapping,
    )


def reconstruct_with_recovery(
    work_dir: Path,
    image_dir: Path,
    names: Sequence[Sequence[str]],
    sharpness: Sequence[Sequence[float]],
    *,
    lens: Lens | None = None,
    stage: Callable[[str], None] | None = None,
    on_image: Callable[[], None] | None = None,
) -> Outcome:
    """Extract features once, then try :data:`STRATEGIES` in order.

    Args:
        work_dir: the COLMAP folder (database, ``sparse/<strategy>/`` models).
        image_dir: folder of the latent frames.
        names: per view, its latent frame file names in time order.
        sharpness: per view, the sharpness of each latent frame.
        lens: the camera's known lens (held fixed), or None to estimate one: a pinhole while
            mapping, then a radial lens where it fits better (:func:`with_radial_lens`).
        stage: called with a stage name when a stage starts (progress display).
        on_image: called when an image registers (progress display).

    Returns:
        The first successful strategy's outcome, else the one that registered the largest
        share of its images (at least ``MINIMUM_FRACTION`` and 3 images).

    Raises:
        ColmapError: no strategy produced a usable model.
    """
    stage = stage or (lambda _name: None)
    stage("features")
    database = extract_features(work_dir, image_dir, [n for view in names for n in view], lens=lens)
    best, tried, matched = None, [], None
    pairs = image_pairs(names, sharpness)
    mapping = {"fixed_intrinsics": lens is not None, "on_image": on_image}

    def kept(model: SparseModel, strategy: Strategy | None, images) -> SparseModel:
        """The model with its lens: the stated one, or one estimated.

        An estimated lens that bends the image's corners is mapped with again (its values
        refined) by ``strategy``.
        """
        if lens is not None:
            return model
        stage("lens")
        estimated = with_radial_lens(model)
        if strategy is None or estimated.lens.corner_shift_px() <= REMAP_SHIFT_PX:
            return estimated
        stage(f"mapping ({strategy.name}, with the estimated lens)")
        use_lens(database, estimated.lens)
        refining = {**mapping, "fixed_intrinsics": False}
        folder = f"{strategy.name}-lens"
        try:
            again = _map(strategy, images, work_dir, image_dir, names, sharpness, refining, folder)
        except ColmapError:
            return estimated
        if again.plausible_camera and len(again.c2w) >= len(estimated.c2w):
            return again
        return estimated

    for strategy in STRATEGIES:
        tried.append(strategy.name)
        if strategy.matcher is not matched:
            which = "" if pairs is None else f", {len(pairs)} pairs of neighbouring views"
            stage(f"matching ({strategy.matcher.value}{which})")
            match_features(database, strategy.matcher, pairs)
            matched = strategy.matcher
        images = _images_of(strategy, names, sharpness)
        stage(f"mapping ({strategy.name})")
        try:
            model = _map(strategy, images, work_dir, image_dir, names, sharpness, mapping)
        except ColmapError:
            continue
        if not (model.plausible_camera or lens is not None):  # a stated camera stands
            continue
        fraction = len(model.c2w) / len(images)
        if fraction >= REGISTERED_FRACTION:
            return Outcome(kept(model, strategy, images), strategy.name, True, tuple(tried))
        if best is None or fraction > best[2]:
            best = (model, strategy.name, fraction)
    if best is None or best[2] < MINIMUM_FRACTION or len(best[0].c2w) < 3:
        raise ColmapError(
            f"COLMAP could not reconstruct these frames (tried {', '.join(tried)}): they show "
            "too little texture, overlap or parallax. Record a scene with more visible detail, "
            "move the camera around rather than only rotating it, or give the camera's "
            "calibration with --camera-calibration"
        )
    # Later strategies replaced the matches this model was made from: its lens is not mapped
    # with again.
    return Outcome(kept(best[0], None, ()), best[1], False, tuple(tried))
