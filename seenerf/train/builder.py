"""The model of a (preset, variant) pair for one scene, on its device: box, field, sensor parts."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import torch
from torch import nn

from seenerf.data.arrays import TrainingData
from seenerf.errors import ConfigError
from seenerf.model.config import FitConfig
from seenerf.model.model import SeeNerfModel
from seenerf.model.pose_correction import PoseCorrection
from seenerf.model.presets import PRESETS, Preset
from seenerf.model.variants import LOW_PASS_READINGS, VARIANTS
from seenerf.render.frustum import forward_facing_space, frustum_box
from seenerf.render.rays import in_any_view, scene_box_from_cameras
from seenerf.render.renderer import RadianceRenderer
from seenerf.sensors.rgb_crf import LinearCrf, MonotoneCrf, RgbCrf, TabulatedCrf

__all__ = [
    "build_model",
    "resolve_device",
    "rgb_response",
    "size_field",
    "with_refined_poses",
]


def resolve_device(name: str) -> str:
    """``auto`` becomes ``cuda`` when a CUDA device is present, else ``cpu``.

    Raises:
        ConfigError: ``cuda`` was asked for and none is present.
    """
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda" and not torch.cuda.is_available():
        raise ConfigError(
            "device cuda was requested but torch sees no CUDA device; use --device cpu"
        )
    return name


def rgb_response(crf: type | None, data: TrainingData, config: FitConfig) -> nn.Module | None:
    """The variant's RGB response for this session.

    The truth's table for the oracle. For the learned response, as ``config.sensor.response``
    says: ``learned`` the MLPs, ``monotone`` the S-curve; ``auto`` the linear one when the
    calibration measured linear frames (a raw DAVIS frame), else the MLPs.

    A linear response whose measured levels cannot hold the anchor falls back to the learned
    one, with a warning: a calibration verdict never stops a fit.

    Raises:
        ConfigError: the oracle's session has no true response.
    """
    if crf is None:
        return None
    if crf is TabulatedCrf:
        if data.truth is None or not len(data.truth.crf_value):
            raise ConfigError(
                "the true response is unknown: this session has no ground truth with a crf/ "
                "(an emulated session's truth/); fit another variant"
            )
        return TabulatedCrf(data.truth.crf_log_exposure, data.truth.crf_value)
    anchor = {
        "anchor_log_exposure": config.sensor.anchor_log_exposure,
        "anchor_value": config.sensor.anchor_value,
    }
    if crf is not RgbCrf or config.sensor.response == "learned":
        return crf(**anchor)
    if config.sensor.response == "monotone":
        return MonotoneCrf(**anchor)
    if data.linear_levels is not None:
        if LinearCrf.fits(*data.linear_levels, config.sensor.anchor_value):
            return LinearCrf(*data.linear_levels, **anchor)
        black, saturation = data.linear_levels
        warnings.warn(
            f"the frames were measured linear, but their black level {black:.3f} and clip level "
            f"{saturation:.3f} leave no room for the anchor value "
            f"{config.sensor.anchor_value}: the response is learned instead",
            stacklevel=2,
        )
    return RgbCrf(**anchor)


def size_field(preset: Preset, span_px: float) -> Preset:
    """Set a grid field's resolution from how many sensor pixels the scene box spans.

    A texel finer than a pixel cannot be constrained by the frames, so the resolution is the
    box's pixel span, at least 48 and at most ``max_resolution``.

    Args:
        preset: a preset whose field has a ``resolution`` argument (others are returned as is).
        span_px: sensor pixels across one side of the box (at the median depth for a world box).
    """
    if "resolution" not in preset.field_args or preset.max_resolution <= 0:
        return preset
    resolution = int(np.clip(span_px, 48, preset.max_resolution))
    return dataclasses.replace(preset, field_args={**preset.field_args, "resolution": resolution})


def build_model(
    data: TrainingData, config: FitConfig, device: str, method: type
) -> tuple[SeeNerfModel, Preset]:
    """The model, and its preset with the configuration's values, its field sized for this scene.

    The field's resolution follows the scene's extent on the sensor (:func:`size_field`).
    ``method`` is the class of the method that will train it
    (:func:`seenerf.train.methods.method_class`): it states the frame the field is trained in
    and whether the poses may be refined.
    """
    variant = VARIANTS[config.model.variant]
    poses, bounds = method.training_frame(data, config, variant)
    preset = PRESETS[config.model.preset]
    space = (
        forward_facing_space(poses, data.intrinsics, bounds, data.image_size)
        if preset.space == "auto"
        else None
    )
    if space is not None:
        box = frustum_box(space, poses, data.intrinsics, bounds, data.image_size)
        view_bounds = np.array([space.near, 1.5 * float(bounds[1])])
        span_px = box.size / 2.0 * data.image_size[1]  # the image spans 2 NDC units
    else:
        box = scene_box_from_cameras(poses, data.intrinsics, bounds, data.image_size)
        view_bounds = bounds
        median_depth = float(np.sqrt(bounds[0] * bounds[1]))
        span_px = float(data.intrinsics[0]) * box.size / median_depth
    stated = {
        "pixels_per_step": config.data.batch_pixels,
        "warm_steps": config.schedule.warm_steps,
        "event_weight": config.model.event_weight,
    }
    preset = dataclasses.replace(
        size_field(preset, span_px),
        **{name: value for name, value in stated.items() if value is not None},
    )
    crf = rgb_response(variant.crf, data, config)
    renderer = RadianceRenderer(preset.field, preset.field_args, preset.sampler, box, space)
    if renderer.grid is not None:

        def to_world(points: torch.Tensor) -> torch.Tensor:
            world = box.to_world(points)
            return space.to_world(world) if space is not None else world

        renderer.grid.restrict_to_views(
            lambda points: torch.as_tensor(
                in_any_view(
                    to_world(points).numpy(),
                    poses[:, :: max(1, poses.shape[1] - 1)],
                    data.intrinsics,
                    view_bounds,
                    data.image_size,
                )
            )
        )
    spec = variant.events
    if spec is not None and spec.delay == "mlp":
        spec = dataclasses.replace(spec, **LOW_PASS_READINGS[config.sensor.low_pass])
    model = SeeNerfModel(
        renderer,
        variant,
        spec,
        float(bounds[0]),
        float(bounds[1]),
        float(np.median(data.exposure_s)),
        crf=crf,
        event_args={
            "threshold": data.threshold,
            "cutoff_hz": data.cutoff_hz or config.sensor.cutoff_hz,
            "dead_time_s": data.dead_time_s if config.sensor.dead_time else 0.0,
            "polarity_scale": data.polarity_scale,
        },
        pose_correction=PoseCorrection(data.num_frames)
        if config.model.refine_poses and method.refines_poses
        else None,
        in_truth_frame=method.in_truth_frame,
    )
    return model.to(device), preset


def with_refined_poses(data: TrainingData, model: SeeNerfModel) -> TrainingData:
    """The training data at the poses the fit refined (as it was when it refined none)."""
    if model.pose_correction is None:
        return data
    return dataclasses.replace(data, c2w=model.pose_correction.apply(data.c2w))
