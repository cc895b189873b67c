"""A small analytic scene with exact truth: a textured HDR plane seen by a shaking camera.

Used by the tests and the benchmark to exercise every part of a fit without a recording: the
blur is the trapezoid integral over finely sampled sub-frames, the LDR response is a known
curve, and events are the ideal log-change counts of each bin, the frames one unbroken stream
whose leads are the ideal change from the first exposure's start.
"""

from __future__ import annotations

import numpy as np

from davis_io.session import DEFAULT_BINS, ColorFilter
from seenerf.data.arrays import TestViews, TrainingData, TrainTruth, pixel_layout

__all__ = ["PLANE_DEPTH", "plane_radiance", "plane_scene", "true_response"]

PLANE_DEPTH = 2.0
"""Depth of the textured plane z = 2 in front of cameras near the origin, world units."""


def true_response(log_exposure: np.ndarray) -> np.ndarray:
    """Known LDR response ``(x / (x + 1))^(1/2.2)`` of x = radiance x seconds."""
    x = np.exp(np.clip(log_exposure, -60, 60))
    return (x / (x + 1.0)) ** (1 / 2.2)


def plane_radiance(x: np.ndarray, y: np.ndarray, dynamic_range: float = 6.0) -> np.ndarray:
    """HDR radiance ``(..., 3)`` of the plane at world (x, y); ln spans about ``dynamic_range``."""
    base = np.sin(3.1 * x) * np.cos(2.3 * y) + 0.5 * np.sin(7.0 * x + 5.0 * y)
    channel_shift = np.array([0.0, 0.6, 1.3])
    log_e = dynamic_range / 3 * (base[..., None] + 0.3 * np.cos(4 * y[..., None] + channel_shift))
    return np.exp(log_e + 3.0).astype(np.float32)


def _c2w(centre: np.ndarray) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = centre
    return pose


def _render(pose: np.ndarray, intrinsics: np.ndarray, height: int, width: int) -> np.ndarray:
    fx, fy, cx, cy = intrinsics
    v, u = np.mgrid[0:height, 0:width].astype(float)
    direction = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], -1) @ pose[:3, :3].T
    t = (PLANE_DEPTH - pose[2, 3]) / direction[..., 2]
    return plane_radiance(pose[0, 3] + t * direction[..., 0], pose[1, 3] + t * direction[..., 1])


def _trapezoid(count: int) -> np.ndarray:
    weights = np.ones(count)
    weights[[0, -1]] = 0.5
    return weights / weights.sum()


def plane_scene(
    height: int = 24,
    width: int = 32,
    frames: int = 6,
    b: int = DEFAULT_BINS,
    exposure_s: float | np.ndarray = 0.016,
    color: ColorFilter = ColorFilter.RGGB,
    shake: float = 0.03,
    test_views: int = 2,
    seed: int = 0,
) -> TrainingData:
    """Blurry LDR frames, ideal event bins and leads, latent poses and truth of the plane scene.

    Args:
        height: image rows.
        width: image columns.
        frames: training frames F.
        b: event bins per exposure.
        exposure_s: exposure of every frame, or ``(F,)`` per frame.
        color: colour filter of the simulated sensor.
        shake: camera travel during one exposure, world units.
        test_views: held-out views.
        seed: trajectory seed.
    """
    rng = np.random.default_rng(seed)
    intrinsics = np.array([0.9 * width, 0.9 * width, (width - 1) / 2, (height - 1) / 2])
    exposure = np.broadcast_to(np.asarray(exposure_s, float), (frames,)).copy()
    sub = 4 * b + 1
    starts = rng.uniform(-0.15, 0.15, (frames, 3)) * [1, 1, 0.5]
    motion = rng.normal(size=(frames, 3)) * [1, 1, 0.2]
    motion = shake * motion / np.linalg.norm(motion, axis=1, keepdims=True)
    fractions = np.linspace(0, 1, sub)
    centres = starts[:, None] + fractions[None, :, None] * motion[:, None]
    truth_c2w = np.stack([[_c2w(c) for c in row] for row in centres])
    sharp = np.stack([[_render(p, intrinsics, height, width) for p in row] for row in truth_c2w])
    blurred = np.einsum("s,fshwc->fhwc", _trapezoid(sub), sharp)
    mix, channel = pixel_layout(color, height, width)
    pixel = (blurred * mix).sum(-1)
    ldr_float = true_response(np.log(pixel) + np.log(exposure)[:, None, None])
    ldr = (np.round(ldr_float * 255) / 255).astype(np.float32)
    latent = sharp[:, ::4]
    log_pixel = np.log((latent * mix).sum(-1))
    bins = (np.diff(log_pixel, axis=1) / 0.3).astype(np.float32)
    lead = ((log_pixel[:, 0] - log_pixel[:1, 0]) / 0.3).astype(np.float32)
    test = _test_views(test_views, intrinsics, height, width, rng) if test_views else None
    return TrainingData(
        ldr=ldr,
        exposure_s=exposure.astype(np.float32),
        weights=np.tile(_trapezoid(b + 1), (frames, 1)).astype(np.float32),
        bins=bins,
        bins_raw=np.trunc(bins).astype(np.float32),
        lead=lead,
        stretch=np.zeros(frames, np.int64),
        c2w=truth_c2w[:, ::4].astype(np.float32),
        intrinsics=intrinsics.astype(np.float32),
        bounds=np.array([1.0, 3.0], np.float32),
        mix=mix,
        channel=channel,
        test=test,
        truth=TrainTruth(
            truth_c2w.astype(np.float32),
            sharp,
            np.linspace(-8, 4, 61),
            np.repeat(true_response(np.linspace(-8, 4, 61))[:, None], 3, 1),
            truth_c2w[:, ::4].astype(np.float32),
        ),
    ).validate()


def _test_views(
    count: int, intrinsics: np.ndarray, height: int, width: int, rng: np.random.Generator
) -> TestViews:
    exposures = np.array([0.001, 0.004, 0.016, 0.064, 0.256])
    c2w = np.stack([_c2w(rng.uniform(-0.1, 0.1, 3) * [1, 1, 0.5]) for _ in range(count)])
    hdr = np.stack([_render(p, intrinsics, height, width) for p in c2w]).reshape(
        count, height, width, 3
    )
    ldr = true_response(np.log(hdr)[:, None] + np.log(exposures)[None, :, None, None, None])
    return TestViews(
        c2w.astype(np.float32),
        hdr.astype(np.float32),
        ldr.astype(np.float32),
        exposures.astype(np.float32),
    )
