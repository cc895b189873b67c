"""Training and test arrays of one scene, checked at the boundary, whatever their source.

Colour sessions store the raw Bayer mosaic. The LDR loss is computed per mosaic pixel on the
channel that pixel records (no demosaicing): a red pixel sees the red radiance through the red
response curve. That keeps the loss physically faithful and keeps demosaicing artefacts out of
the training signal. Monochrome pixels see the luminance of the three rendered channels through
one response curve (the first of the three).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from davis_io.session import ColorFilter, filter_weights
from seenerf.errors import TrainingDataError

__all__ = ["CLIP_MARGIN", "TestViews", "TrainTruth", "TrainingData", "pixel_layout"]

CLIP_MARGIN = 0.02
"""Frame values this close below the frames' clip level count as clipped."""


def pixel_layout(
    color_filter: ColorFilter, height: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel colour weights and response-curve channel from a recorded colour filter.

    Args:
        color_filter: the sensor's pattern (``RGGB``: (even row, even column) red).
        height: image rows.
        width: image columns.

    Returns:
        ``mix`` ``(H, W, 3)`` float32 weights of linear R, G, B summed by each pixel (the same
        weights the emulator uses), and ``channel`` ``(H, W)`` int64 index of the RGB response
        curve the pixel goes through: its colour for R, G, B sites, the first curve for
        monochrome and white sites.
    """
    mix = filter_weights(color_filter, height, width).astype(np.float32)
    one_hot = mix.max(axis=-1) == 1.0
    channel = np.where(one_hot, mix.argmax(axis=-1), 0)
    return mix, channel.astype(np.int64)


@dataclass
class TestViews:
    """Ground-truth views never seen in training, at the true poses (truth frame).

    Attributes:
        c2w: ``(T, 4, 4)`` camera-to-world, OpenCV axes, truth frame.
        hdr: ``(T, H, W, 3)`` float32 linear HDR radiance.
        ldr: ``(T, E, H, W, C)`` float32 LDR in [0, 1] at ``exposures_s`` (C = 3 RGB or 1).
        exposures_s: ``(E,)`` exposure times in seconds of the LDR bracket.
    """

    c2w: np.ndarray
    hdr: np.ndarray
    ldr: np.ndarray
    exposures_s: np.ndarray


@dataclass
class TrainTruth:
    """Ground truth of the training views (emulated sessions only).

    Attributes:
        c2w: ``(F, S, 4, 4)`` true camera-to-world at S sub-frame times of each exposure.
        sharp_hdr: ``(F, S, H, W, 3)`` float32 sharp linear HDR at those times.
        crf_log_exposure: ``(K,)`` ln(radiance x seconds) samples of the true response, or empty.
        crf_value: ``(K, 3)`` true LDR response at those samples, or empty.
        latent_c2w: ``(F, b+1, 4, 4)`` true poses at the latent time points, when known.
    """

    c2w: np.ndarray
    sharp_hdr: np.ndarray
    crf_log_exposure: np.ndarray
    crf_value: np.ndarray
    latent_c2w: np.ndarray | None = None


@dataclass
class TrainingData:
    """Everything a fit reads, as float32 arrays; see :meth:`validate` for the invariants.

    Attributes:
        ldr: ``(F, H, W)`` raw sensor values in [0, 1] (10-bit / 1023, 8-bit / 255).
        exposure_s: ``(F,)`` exposure time of each frame, seconds.
        weights: ``(F, b+1)`` trapezoid weights of the exposure integral, rows sum to 1.
        bins: ``(F, b, H, W)`` ln intensity change of each bin in units of ``threshold``: the
            events weighted by their pixel's calibrated thresholds, with the h() offsets.
        bins_raw: ``(F, b, H, W)`` signed integer event counts without offsets.
        settled: ``(F, b+1, H, W)`` bool, where a pixel had fired all it owed at a latent time
            point (:func:`davis_io.settled.settled_points`); None: everywhere.
        lead: ``(F, H, W)`` ln change in units of ``threshold`` from the first exposure of the
            frame's unbroken stretch of the stream to its start (the bins and the events between
            exposures); None: the stream's changes between exposures are not known.
        stretch: ``(F,)`` int64, which stretch each frame belongs to (with ``lead``).
        c2w: ``(F, b+1, 4, 4)`` camera-to-world per latent time point, OpenCV axes.
        intrinsics: ``(4,)`` fx, fy, cx, cy in pixels.
        distortion: the lens's OpenCV coefficients ``k1, k2, p1, p2[, k3 ...]`` (empty: a
            pinhole).
        bounds: ``(2,)`` near and far depth of the scene along the optical axis.
        mix: ``(H, W, 3)`` linear RGB weights each pixel sums (colour filter).
        channel: ``(H, W)`` int64 response-curve channel of each pixel.
        monochrome: the sensor has no colour filter: renders are luminance, one channel.
        threshold: the unit of ``bins``: the mean of the calibrated ON and OFF thresholds.
        cutoff_hz: the photoreceptor cut-off the calibration knows, or 0 (the config's then).
        dead_time_s: the pixels' measured dead time, or 0 when none was measured.
        polarity_scale: the calibrated ON and OFF thresholds over ``threshold``.
        thresholds_measured: the thresholds were measured or stated (False: the calibration
            could not measure them and the nominal ones stand in).
        linear_levels: ``(black, saturation)`` normalised, when the calibration measured frames
            linear in exposure (a raw DAVIS frame); None otherwise.
        clip_level: normalised value where the frames clip (the calibration's; 1 where they
            never pile up at a top value).
        noise_offset: for linear frames whose noise was measured, the value above black where
            their shot noise equals their read noise (normalised); 0 otherwise.
        test: held-out views with truth, if any.
        truth: training-view truth, if any (emulated sessions).
    """

    ldr: np.ndarray
    exposure_s: np.ndarray
    weights: np.ndarray
    bins: np.ndarray
    bins_raw: np.ndarray
    c2w: np.ndarray
    intrinsics: np.ndarray
    bounds: np.ndarray
    mix: np.ndarray
    channel: np.ndarray
    settled: np.ndarray | None = None
    lead: np.ndarray | None = None
    stretch: np.ndarray | None = None
    monochrome: bool = False
    threshold: float = 0.3
    cutoff_hz: float = 0.0
    dead_time_s: float = 0.0
    polarity_scale: tuple[float, float] = (1.0, 1.0)
    thresholds_measured: bool = True
    linear_levels: tuple[float, float] | None = None
    clip_level: float = 1.0
    noise_offset: float = 0.0
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(0, np.float32))
    test: TestViews | None = None
    truth: TrainTruth | None = None

    @property
    def num_frames(self) -> int:
        """Number of training frames F."""
        return int(self.ldr.shape[0])

    @property
    def num_bins(self) -> int:
        """Event bins per exposure b."""
        return int(self.bins.shape[1])

    @property
    def lone_frames(self) -> np.ndarray:
        """``(F,)`` bool: frames alone in their stretch of the event stream.

        No events tie such a frame to another (a recording made view by view, or exposures
        between gaps): only its own exposure's events tell what it clipped. All False where the
        stretches are not known.
        """
        if self.stretch is None:
            return np.zeros(self.num_frames, bool)
        _, which, members = np.unique(self.stretch, return_inverse=True, return_counts=True)
        return members[which] == 1

    def clipped(self, values):
        """Whether each frame value (array or tensor) is at the clip level or above.

        Values within :data:`CLIP_MARGIN` below it count as clipped.
        """
        return values >= self.clip_level - CLIP_MARGIN

    @property
    def image_size(self) -> tuple[int, int]:
        """Sensor ``(height, width)`` in pixels."""
        return int(self.ldr.shape[1]), int(self.ldr.shape[2])

    def validate(self) -> TrainingData:
        """Check shapes, dtypes and ranges; return self.

        Raises:
            TrainingDataError: naming the array, what it should be and what it is.
        """
        frames, height, width = self.ldr.shape if self.ldr.ndim == 3 else (0, 0, 0)
        if self.ldr.ndim != 3 or frames == 0:
            raise TrainingDataError(f"ldr must be (F, H, W) with F >= 1, got {self.ldr.shape}")
        b = self.bins.shape[1] if self.bins.ndim == 4 else 0
        expected = {
            "exposure_s": (frames,),
            "weights": (frames, b + 1),
            "bins": (frames, b, height, width),
            "bins_raw": (frames, b, height, width),
            "c2w": (frames, b + 1, 4, 4),
            "intrinsics": (4,),
            "bounds": (2,),
            "mix": (height, width, 3),
            "channel": (height, width),
        }
        if self.settled is not None:
            expected["settled"] = (frames, b + 1, height, width)
        if (self.lead is None) != (self.stretch is None):
            raise TrainingDataError("TrainingData.lead and .stretch come together, or neither")
        if self.lead is not None:
            expected["lead"] = (frames, height, width)
            expected["stretch"] = (frames,)
        for name, shape in expected.items():
            value = getattr(self, name)
            if value.shape != shape or b < 1:
                raise TrainingDataError(
                    f"TrainingData.{name} has shape {value.shape}, expected {shape} "
                    f"(F={frames}, b={b}, H={height}, W={width}); rebuild the session bins"
                )
            if name != "channel" and not np.all(np.isfinite(value)):
                raise TrainingDataError(f"TrainingData.{name} holds NaN or inf values")
        if self.ldr.min() < 0 or self.ldr.max() > 1:
            raise TrainingDataError("TrainingData.ldr must lie in [0, 1]; divide by 1023 or 255")
        if np.any(self.exposure_s <= 0):
            raise TrainingDataError("TrainingData.exposure_s must be > 0 seconds for every frame")
        if not np.allclose(self.weights.sum(axis=1), 1.0, atol=1e-3):
            raise TrainingDataError("TrainingData.weights rows must sum to 1 (trapezoid weights)")
        if not 0 < self.bounds[0] < self.bounds[1]:
            raise TrainingDataError(
                f"TrainingData.bounds must be 0 < near < far, got {self.bounds}"
            )
        return self
