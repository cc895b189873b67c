"""What differs between variants, resolved once at the start of a fit into a method.

A method owns what it trains on (the recorded frames and events at the estimated poses, or the
truth's sharp HDR at the true poses), its batches, its loss terms, each with its weight and its
name in the log, and its held-out score. The training loop (:mod:`seenerf.train.trainer`) asks
a method for the terms of a step and its score, and never which variant it serves.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from seenerf.data.arrays import TrainingData
from seenerf.data.batching import FrameSampler, SharpTruthSampler
from seenerf.data.frames import truth_to_fit_frame
from seenerf.errors import ConfigError, OptionError
from seenerf.eval.metrics import psnr
from seenerf.model.config import FitConfig
from seenerf.model.model import SeeNerfModel
from seenerf.model.pose_correction import PRIOR_WEIGHT as POSE_PRIOR_WEIGHT
from seenerf.model.presets import Preset
from seenerf.model.variants import VARIANTS, Variant
from seenerf.train.builder import build_model, resolve_device
from seenerf.train.losses import (
    event_loss,
    exposure_loss,
    hdr_tone_map,
    ldr_loss,
    noise_even,
    sharp_hdr_loss,
    span_loss,
    tone_mapped_render,
)

__all__ = [
    "METHODS",
    "LossTerm",
    "Method",
    "RecordingMethod",
    "SharpTruthMethod",
    "Step",
    "frame_scale",
    "make_method",
    "method_class",
]

VALIDATION_CHUNK = 2048
"""Held-out pixels rendered at once."""


@dataclass(frozen=True)
class LossTerm:
    """One term of a step's loss: the loss adds ``weight * value``; the log shows ``value``."""

    name: str
    weight: float
    value: torch.Tensor


@dataclass(frozen=True)
class Step:
    """A step's loss terms and what it rendered (rays, and field samples per ray's last pass)."""

    terms: list[LossTerm]
    rays: int
    samples: int

    def loss(self) -> torch.Tensor:
        """The weighted sum of the terms, in their order."""
        total = self.terms[0].weight * self.terms[0].value
        for term in self.terms[1:]:
            total = total + term.weight * term.value
        return total

    def shown(self) -> dict[str, float]:
        """Each term's value by name, for the log."""
        return {term.name: float(term.value.detach()) for term in self.terms}


def frame_scale(data: TrainingData, config: FitConfig) -> Callable[[torch.Tensor], torch.Tensor]:
    """The scale frame values are compared on.

    Noise-even (:func:`~seenerf.train.losses.noise_even`) for linear frames whose noise was
    measured, unless ``config.sensor.frame_noise`` is off; else the values themselves.
    """
    if not config.sensor.frame_noise or data.linear_levels is None or data.noise_offset <= 0:
        return lambda values: values
    black, offset = data.linear_levels[0], data.noise_offset
    return lambda values: noise_even(values, black, offset)


class Method:
    """The part of a fit that depends on its variant.

    Class attributes, read before a model exists (:func:`method_class`):
    ``in_truth_frame``, the field is trained in the truth's frame (test poses need no mapping);
    ``refines_poses``, the training poses may be refined with the field.

    Args:
        model: the model being trained.
        data: the training arrays.
        config: the fit configuration.
        preset: the scene's preset with the configuration's values
            (:func:`~seenerf.train.builder.build_model`).
        device: torch device.

    Attributes:
        validation: flat indices ``frame * H * W + pixel`` of the held-out training pixels
            (drawn at the configuration's seed, never trained on).
    """

    in_truth_frame = False
    refines_poses = True

    @classmethod
    def training_frame(
        cls, data: TrainingData, config: FitConfig, variant: Variant
    ) -> tuple[np.ndarray, np.ndarray]:
        """Poses the field is trained at and the scene's near / far depth in their frame."""
        return data.c2w, data.bounds

    def __init__(
        self,
        model: SeeNerfModel,
        data: TrainingData,
        config: FitConfig,
        preset: Preset,
        device: str,
    ):
        self.model, self.data, self.config, self.preset = model, data, config, preset
        self.device = device
        rng = np.random.default_rng(config.schedule.seed)
        pixels = data.image_size[0] * data.image_size[1]
        count = int(round(config.data.validation_share * data.num_frames * pixels))
        chosen = rng.choice(data.num_frames * pixels, count, False)
        self.validation = torch.as_tensor(np.sort(chosen))

    @property
    def clips_hard(self) -> bool:
        """True when the model's response has no gradient above its clip level."""
        return self.model.crf is not None and self.model.crf.clips_hard

    def step(self, generator: torch.Generator) -> Step:
        """The loss terms of one random batch."""
        raise NotImplementedError

    def validation_psnr(self) -> float:
        """The held-out score, dB (nan without held-out pixels)."""
        raise NotImplementedError

    def _smoothness(self) -> list[LossTerm]:
        """The field's total variation, where the preset weighs it and the field has one."""
        smoothness = getattr(self.model.renderer.fields[0], "smoothness", None)
        if smoothness is None or self.preset.smoothness <= 0:
            return []
        return [LossTerm("smoothness", self.preset.smoothness, smoothness())]


class RecordingMethod(Method):
    """Trains on the recorded blurry frames and their events, at the estimated poses.

    The terms: the frames' LDR error (eq. 15), the events' (weighted by the preset's lambda,
    the more where a frame clipped), lone frames' whole exposures' and the spans' between
    frames (each weighted as the events, the more where a frame clipped), the response's
    anchor, the field's smoothness, and the prior of refined poses.
    """

    @classmethod
    def training_frame(
        cls, data: TrainingData, config: FitConfig, variant: Variant
    ) -> tuple[np.ndarray, np.ndarray]:
        """The estimated latent poses and their bounds.

        Raises:
            ConfigError: the variant needs frames of several exposures and the session has one.
        """
        if variant.several_exposures:
            if len(np.unique(data.exposure_s)) < 2:
                raise ConfigError(
                    f"variant {config.model.variant} needs frames of at least two exposures; this "
                    f"session has one ({float(data.exposure_s[0]):g} s): record with several "
                    "exposures"
                )
        return data.c2w, data.bounds

    def __init__(self, model, data, config, preset, device):
        super().__init__(model, data, config, preset, device)
        events = model.variant.events
        self.frames = FrameSampler(
            data,
            np.arange(data.num_frames),
            event_share=config.data.event_share,
            calibrated=events is None or events.calibrated,
            exclude=self.validation.numpy(),
            device=device,
            subframes=config.model.subframes,
            dead_time=config.sensor.dead_time,
            lone_exposure_spans=config.data.lone_exposure_spans,
            correction=model.pose_correction,
        )
        self.scale = frame_scale(data, config)
        self.zero = torch.zeros((), device=device)
        calibrated = events is not None and events.calibrated
        spans = calibrated and data.lead is not None
        self.spans = round(config.data.span_share * preset.pixels_per_step) if spans else 0
        self.lone_exposures = config.data.lone_exposure_spans and bool(data.lone_frames.any())

    def step(self, generator: torch.Generator) -> Step:
        """The loss terms of a batch of recorded pixels."""
        model = self.model
        batch = self.frames.sample(self.preset.pixels_per_step, generator)
        predictions = model(batch, generator)
        recorded = self.scale(batch.ldr)
        weights = self.event_weights(batch.ldr)
        ldr = sum(ldr_loss(self.scale(p.ldr), recorded) for p in predictions)
        events = sum(
            (
                event_loss(p.counts, batch.bins, batch.settled, weights)
                for p in predictions
                if p.counts is not None
            ),
            self.zero,
        )
        anchor = model.crf.anchor_loss() if model.crf is not None else self.zero
        terms = [
            LossTerm("ldr", 1.0, ldr),
            LossTerm("events", self.preset.event_weight, events),
            *self._exposures(predictions, batch, weights),
            *self._spans(generator),
            LossTerm("anchor", self.config.sensor.anchor_weight, anchor),
            *self._smoothness(),
        ]
        if model.pose_correction is not None:
            terms.append(LossTerm("poses", POSE_PRIOR_WEIGHT, model.pose_correction.prior()))
        rays = batch.origins.shape[0] * batch.origins.shape[1] + 2 * self.spans
        return Step(terms, rays, predictions[-1].num_samples)

    def event_weights(self, ldr: torch.Tensor) -> torch.Tensor | None:
        """Each pixel's weight on its events: the preset's factor where its frame clipped.

        ``ldr`` holds the pixels' recorded values, ``(R,)``, or ``(R, k)`` for events that
        span k frames (a span between two): the factor where any of them clipped.

        Only where the thresholds were measured: nothing else checks a clipped pixel's events,
        so they would carry a nominal threshold's error (± 50 %) into the light unchecked. And
        only where the response clips hard (a raw sensor's line): a curve that flattens
        smoothly still tells the field how far above the clip level a pixel lay, and there the
        factor pulled the light against the frames (corridor-s106: 1.3 dB lower, the contrast
        0.87 from 1.00).
        """
        factor = self.preset.clipped_event_factor
        if factor == 1.0 or not self.data.thresholds_measured or not self.clips_hard:
            return None
        clipped = self.data.clipped(ldr).reshape(len(ldr), -1).any(dim=1)
        return torch.where(clipped, factor, 1.0)

    def _exposures(self, predictions, batch, weights) -> list[LossTerm]:
        """The whole exposures' term, where the session has lone frames and the variant events.

        Bin by bin, a lone frame's events ask the field for each edge's crossing within a bin
        its poses cannot place that finely; over the whole exposure, for the change alone.
        """
        if not self.lone_exposures or predictions[-1].counts is None:
            return []
        error = sum(
            exposure_loss(p.counts, batch.bins, batch.settled, batch.lone, weights)
            for p in predictions
        )
        return [LossTerm("exposures", self.preset.event_weight, error)]

    def _spans(self, generator: torch.Generator) -> list[LossTerm]:
        """The spans' term, where the method draws spans."""
        if not self.spans:
            return []
        spans = self.frames.spans(self.spans, self.config.data.span_reach, generator)
        changes = self.model.span_changes(spans, generator)
        weights = self.event_weights(spans.ldr)
        error = sum(span_loss(change, spans.change, spans.known, weights) for change in changes)
        return [LossTerm("spans", self.preset.event_weight, error)]

    @torch.no_grad()
    def validation_psnr(self) -> float:
        """LDR PSNR of the held-out training pixels (the blurry frames reproduced), dB."""
        if len(self.validation) == 0:
            return math.nan
        predicted, recorded = [], []
        for chunk in self.validation.split(VALIDATION_CHUNK):
            batch = self.frames.batch_flat(chunk)
            predicted.append(self.model(batch)[-1].ldr.cpu())
            recorded.append(batch.ldr.cpu())
        return psnr(torch.cat(predicted).numpy(), torch.cat(recorded).numpy())


class SharpTruthMethod(Method):
    """The oracle: trains on the truth's sharp linear HDR at the true poses.

    The terms: the tone-mapped HDR error and the field's smoothness.
    """

    in_truth_frame = True
    refines_poses = False

    @classmethod
    def training_frame(
        cls, data: TrainingData, config: FitConfig, variant: Variant
    ) -> tuple[np.ndarray, np.ndarray]:
        """The truth's poses, with the bounds rescaled into the truth's frame.

        (Estimated poses are known up to a similarity.)

        Raises:
            ConfigError: the session has no truth.
        """
        if data.truth is None:
            raise ConfigError(
                f"variant {config.model.variant} needs ground truth (an emulated session with "
                "truth/)"
            )
        scale = truth_to_fit_frame(data).scale
        return data.truth.c2w, (np.asarray(data.bounds, np.float64) / scale).astype(np.float32)

    def __init__(self, model, data, config, preset, device):
        super().__init__(model, data, config, preset, device)
        truth = data.truth
        self.truth = SharpTruthSampler(
            truth.c2w, truth.sharp_hdr, data.intrinsics, data.distortion, device
        )

    def step(self, generator: torch.Generator) -> Step:
        """The loss terms of a batch of sharp truth pixels."""
        count = self.preset.pixels_per_step * (self.data.num_bins + 1)
        origins, directions, hdr = self.truth.sample(count, generator)
        model = self.model
        passes = model.renderer(origins, directions, model.near, model.far, None, generator)
        error = sum(sharp_hdr_loss(p.values, hdr, self.truth.scale) for p in passes)
        terms = [LossTerm("hdr", 1.0, error), *self._smoothness()]
        return Step(terms, len(origins), passes[-1].num_samples)

    @torch.no_grad()
    def validation_psnr(self) -> float:
        """Tone-mapped HDR PSNR of the held-out pixel indices in the sharp truth images, dB."""
        if len(self.validation) == 0:
            return math.nan
        images, height, width = self.truth.hdr.shape[:3]
        predicted, true = [], []
        for chunk in (self.validation % (images * height * width)).split(VALIDATION_CHUNK):
            origins, directions, hdr = self.truth.pixels(chunk.to(self.truth.hdr.device))
            log_radiance = self.model.render_log_radiance(origins, directions)
            predicted.append(tone_mapped_render(log_radiance, self.truth.scale))
            true.append(hdr_tone_map(hdr, self.truth.scale))
        return psnr(torch.cat(predicted).cpu().numpy(), torch.cat(true).cpu().numpy())


METHODS: dict[str, type[Method]] = {
    "recording": RecordingMethod,
    "sharp-truth": SharpTruthMethod,
}
"""Every method by the name a variant gives (:attr:`seenerf.model.variants.Variant.method`)."""


def method_class(variant: Variant) -> type[Method]:
    """The method that trains ``variant``.

    Raises:
        OptionError: the variant names no known method (the message lists them).
    """
    if variant.method not in METHODS:
        raise OptionError(f"unknown method {variant.method!r}; choose one of: {', '.join(METHODS)}")
    return METHODS[variant.method]


def make_method(data: TrainingData, config: FitConfig) -> Method:
    """The method of the configuration's variant, with the model it trains built for this scene.

    The model is built on the configuration's device, its weights drawn at its seed.
    """
    torch.manual_seed(config.schedule.seed)
    method = method_class(VARIANTS[config.model.variant])
    device = resolve_device(config.schedule.device)
    model, preset = build_model(data, config, device, method)
    return method(model, data, config, preset, device)
