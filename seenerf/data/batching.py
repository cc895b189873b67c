"""Random pixel batches of training frames, of spans between frames, and of the oracle's truth.

A training pixel is seen from every pose of its exposure; a span is one pixel at latent points
of two frames of one stretch of the stream.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from seenerf.data.arrays import TrainingData
from seenerf.data.subframes import refine_exposure
from seenerf.model.imaging import RayBatch, SpanBatch
from seenerf.render.rays import camera_rays, pixel_coordinates, rays_through

__all__ = ["FrameSampler", "SharpTruthSampler"]


class FrameSampler:
    """Draws pixels of the blurry training frames, a share of them where events fired.

    Args:
        data: the training arrays.
        frames: indices of the frames to train on.
        event_share: fraction of each batch drawn among pixels with at least one event.
        calibrated: batches carry the h()-calibrated counts (True) or the raw integer counts.
        exclude: flat indices ``position_in_frames * H * W + pixel`` never drawn (validation).
        device: torch device.
        subframes: sub-frames per bin of the exposure integral (:mod:`seenerf.data.subframes`).
        dead_time: the fit models the pixels' dead time, so batches carry where each pixel was
            settled (``data.settled``); False: every latent point counts as settled, so each bin
            is compared alone.
        lone_exposure_spans: batches mark the pixels of frames alone in their stretch of the
            stream (``data.lone_frames``), whose events are compared over their whole exposure
            as well (:func:`seenerf.train.losses.exposure_loss`).
        correction: ``correction(c2w, frame)`` gives a batch's poses as the fit refines them
            (:class:`~seenerf.model.pose_correction.PoseCorrection`), or None for the poses
            as given.
    """

    def __init__(
        self,
        data: TrainingData,
        frames: np.ndarray,
        *,
        event_share: float = 0.5,
        calibrated: bool = True,
        exclude: np.ndarray | None = None,
        device: str = "cpu",
        subframes: int = 1,
        dead_time: bool = True,
        lone_exposure_spans: bool = False,
        correction: Callable[[torch.Tensor, torch.Tensor], torch.Tensor] | None = None,
    ):
        self.height, self.width = data.image_size
        self.frames = torch.as_tensor(frames, dtype=torch.long)
        self.ldr = torch.as_tensor(data.ldr, device=device)
        self.exposure_s = torch.as_tensor(data.exposure_s, device=device)
        c2w, weights = refine_exposure(data.c2w, data.weights, subframes)
        self.subframes = subframes
        self.weights = torch.as_tensor(weights, device=device)
        self.c2w = torch.as_tensor(c2w, device=device)
        self.intrinsics = torch.as_tensor(data.intrinsics, device=device)
        lens = torch.as_tensor(data.distortion, device=device)
        self.pixel_xy = torch.stack(
            pixel_coordinates(self.intrinsics, data.image_size, lens), dim=-1
        )
        self.mix = torch.as_tensor(data.mix, device=device).reshape(-1, 3)
        self.channel = torch.as_tensor(data.channel, device=device).reshape(-1)
        self.bins = torch.as_tensor(data.bins if calibrated else data.bins_raw, device=device)
        shape = (data.num_frames, data.num_bins + 1, self.height, self.width)
        known = data.settled if dead_time and data.settled is not None else np.ones(shape, bool)
        self.settled = torch.as_tensor(known, device=device)
        lone = data.lone_frames if lone_exposure_spans else np.zeros(data.num_frames, bool)
        self.lone = torch.as_tensor(lone, device=device)
        self.device = device
        self.level = _levels(data, device)
        self.stretch_first, self.stretch_last = _stretch_ends(data, frames)
        allowed = np.ones(len(frames) * self.height * self.width, bool)
        allowed[np.asarray(exclude if exclude is not None else [], np.int64)] = False
        active = np.abs(data.bins_raw[frames]).sum(axis=1).reshape(-1) > 0
        self.pool = torch.as_tensor(np.flatnonzero(allowed), dtype=torch.long)
        self.event_pool = torch.as_tensor(np.flatnonzero(allowed & active), dtype=torch.long)
        self.event_share = event_share if len(self.event_pool) else 0.0
        self.correction = correction

    def sample(self, count: int, generator: torch.Generator) -> RayBatch:
        """``count`` random pixels of random training frames."""
        return self.batch_flat(self._draw(count, generator))

    def _draw(self, count: int, generator: torch.Generator) -> torch.Tensor:
        """Flat indices of ``count`` random pixels, the event share among pixels with events."""
        from_events = int(round(count * self.event_share))
        uniform = self.pool[
            torch.randint(len(self.pool), (count - from_events,), generator=generator)
        ]
        picks = (
            self.event_pool[
                torch.randint(len(self.event_pool), (from_events,), generator=generator)
            ]
            if from_events
            else uniform[:0]
        )
        return torch.cat([uniform, picks])

    def spans(self, count: int, reach: int, generator: torch.Generator) -> SpanBatch:
        """``count`` random pixels, each at a latent point of two training frames of one stretch.

        The first frame and pixel are drawn as :meth:`sample` draws them, the second frame up to
        ``reach`` frames away within the first's stretch, each latent point at random.

        Raises:
            ValueError: the data hold no leads (:attr:`TrainingData.lead`).
        """
        if self.level is None:
            raise ValueError("spans need the stream's changes between exposures (lead)")
        pixels = self.height * self.width
        flat = self._draw(count, generator)
        position, pixel = flat // pixels, flat % pixels
        low = torch.maximum(self.stretch_first[position], position - reach)
        high = torch.minimum(self.stretch_last[position], position + reach)
        share = torch.rand(position.shape, generator=generator)
        other = torch.minimum(low + (share * (high - low + 1)).long(), high)
        frame = torch.stack([self.frames[position], self.frames[other]], dim=1).to(self.device)
        points = self.level.shape[1]
        point = torch.randint(points, frame.shape, generator=generator).to(self.device)
        pixel = pixel.to(self.device)
        v = torch.div(pixel, self.width, rounding_mode="floor")[:, None]
        u = (pixel % self.width)[:, None]
        c2w = self.c2w[:, :: self.subframes][frame, point]
        if self.correction is not None:
            c2w = self.correction(c2w.reshape(-1, 1, 4, 4), frame.reshape(-1)).reshape(c2w.shape)
        xy = self.pixel_xy[pixel].repeat_interleave(2, dim=0)
        origins, directions = rays_through(c2w.reshape(-1, 4, 4), xy[:, 0], xy[:, 1])
        level = self.level[frame, point, v, u]
        settled = self.settled[frame, point, v, u]
        return SpanBatch(
            origins.reshape(-1, 2, 3),
            directions.reshape(-1, 2, 3),
            self.mix[pixel],
            level[:, 1] - level[:, 0],
            settled.all(dim=1),
            self.ldr[frame, v, u],
        )

    def batch_flat(self, flat: torch.Tensor) -> RayBatch:
        """The :class:`RayBatch` of flat indices ``position_in_frames * H * W + pixel``."""
        pixels = self.height * self.width
        return self.batch(self.frames[flat // pixels], flat % pixels)

    def batch(self, frame: torch.Tensor, pixel: torch.Tensor) -> RayBatch:
        """The :class:`RayBatch` of given frame indices and flat pixel indices."""
        frame, pixel = frame.to(self.device), pixel.to(self.device)
        v = torch.div(pixel, self.width, rounding_mode="floor")
        u = pixel % self.width
        c2w = self.c2w[frame]
        if self.correction is not None:
            c2w = self.correction(c2w, frame)
        poses = c2w.shape[1]
        xy = self.pixel_xy[pixel].repeat_interleave(poses, dim=0)
        origins, directions = rays_through(c2w.reshape(-1, 4, 4), xy[:, 0], xy[:, 1])
        return RayBatch(
            origins.reshape(-1, poses, 3),
            directions.reshape(-1, poses, 3),
            self.weights[frame],
            self.exposure_s[frame],
            self.mix[pixel],
            self.channel[pixel],
            self.ldr[frame, v, u],
            self.bins[frame, :, v, u],
            self.settled[frame, :, v, u],
            self.subframes,
            self.lone[frame],
        )


def _levels(data: TrainingData, device: str) -> torch.Tensor | None:
    """Each pixel's ln level at each latent point, ``(F, b+1, H, W)`` (None without leads).

    The change from the start of the frame's stretch of the stream, in thresholds.
    """
    if data.lead is None:
        return None
    within = np.cumsum(data.bins, axis=1)
    level = np.concatenate([data.lead[:, None], data.lead[:, None] + within], axis=1)
    return torch.as_tensor(level.astype(np.float32), device=device)


def _stretch_ends(data: TrainingData, frames: np.ndarray) -> tuple[torch.Tensor, torch.Tensor]:
    """Per position in ``frames``: the first and last position of its run of one stretch."""
    stretch = np.zeros(len(frames)) if data.stretch is None else data.stretch[frames]
    starts = np.concatenate([[True], stretch[1:] != stretch[:-1]])
    run = np.cumsum(starts) - 1
    first = np.flatnonzero(starts)
    last = np.concatenate([first[1:], [len(frames)]]) - 1
    return torch.as_tensor(first[run]), torch.as_tensor(last[run])


class SharpTruthSampler:
    """Draws sharp truth HDR pixels of the training views at their true poses.

    Args:
        c2w: ``(F, S, 4, 4)`` true poses; ``hdr`` ``(F, S, H, W, 3)`` sharp HDR.
        intrinsics: fx, fy, cx, cy.
        distortion: the lens's OpenCV coefficients (empty: a pinhole).
    """

    def __init__(
        self,
        c2w: np.ndarray,
        hdr: np.ndarray,
        intrinsics: np.ndarray,
        distortion: np.ndarray,
        device: str = "cpu",
    ):
        self.c2w = torch.as_tensor(c2w, dtype=torch.float32, device=device).reshape(-1, 4, 4)
        self.hdr = torch.as_tensor(hdr, dtype=torch.float32, device=device)
        self.hdr = self.hdr.reshape(-1, *self.hdr.shape[-3:])
        self.intrinsics = torch.as_tensor(intrinsics, dtype=torch.float32, device=device)
        self.distortion = torch.as_tensor(distortion, dtype=torch.float32, device=device)
        self.scale = float(self.hdr.max())

    def sample(self, count: int, generator: torch.Generator):
        """``(origins, directions, hdr)`` of ``count`` random truth pixels."""
        images, height, width = self.hdr.shape[:3]
        flat = torch.randint(images * height * width, (count,), generator=generator)
        return self.pixels(flat)

    def pixels(self, flat: torch.Tensor):
        """``(origins, directions, hdr)`` of truth pixels at flat ``image * H * W + pixel``."""
        height, width = self.hdr.shape[1:3]
        image, pixel = flat // (height * width), flat % (height * width)
        v, u = pixel // width, pixel % width
        origins, directions = camera_rays(
            self.c2w[image], self.intrinsics, u.float(), v.float(), self.distortion
        )
        return origins, directions, self.hdr[image, v, u]
