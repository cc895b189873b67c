"""See-NeRF composed from named parts: radiance renderer, exposure integral, RGB CRF, event CRF."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from seenerf.model.imaging import RayBatch, SpanBatch
from seenerf.model.pose_correction import PoseCorrection
from seenerf.model.variants import Variant
from seenerf.render.renderer import RadianceRenderer
from seenerf.sensors.event_crf import EventCrf, EventModelSpec

__all__ = ["Prediction", "SeeNerfModel"]


@dataclass
class Prediction:
    """One rendering pass's prediction for a :class:`RayBatch`."""

    ldr: torch.Tensor
    counts: torch.Tensor | None
    log_radiance: torch.Tensor
    num_samples: int


class SeeNerfModel(nn.Module):
    """The whole imaging model of a variant.

    Args:
        renderer: field + sampler + volume rendering.
        variant: which parts are used.
        event_spec: the event model (the variant's, possibly with another low-pass reading).
        near: near depth; ``far`` far depth.
        reference_exposure_s: exposure of the training frames (for the LDR-field variant).
        crf: the RGB response (built for the session: :func:`seenerf.train.builder.rgb_response`)
            or None; ``event_args``: keyword arguments of the event CRF.
        pose_correction: the training views' learned pose corrections, or None when the
            poses are taken as given.
        in_truth_frame: the field was trained in the truth's frame (at its poses), so test
            poses need no mapping from the training cameras.
    """

    def __init__(
        self,
        renderer: RadianceRenderer,
        variant: Variant,
        event_spec: EventModelSpec | None,
        near: float,
        far: float,
        reference_exposure_s: float,
        crf: nn.Module | None,
        event_args: dict,
        pose_correction: PoseCorrection | None = None,
        in_truth_frame: bool = False,
    ):
        super().__init__()
        self.renderer = renderer
        self.variant = variant
        self.near, self.far = near, far
        self.reference_exposure_s = reference_exposure_s
        self.crf = crf
        self.event_crf = EventCrf(event_spec, **event_args) if event_spec is not None else None
        self.pose_correction = pose_correction
        self.in_truth_frame = in_truth_frame

    def warm_start(self, steps: int, seed: int) -> None:
        """Reference warm start of the response MLPs (before any training step)."""
        if self.crf is not None:
            self.crf.warm_start(steps, seed=seed)
        if self.event_crf is not None:
            self.event_crf.warm_start(steps, seed=seed + 1)

    def forward(
        self, batch: RayBatch, generator: torch.Generator | None = None
    ) -> list[Prediction]:
        """Predicted blurry LDR values and event counts, one :class:`Prediction` per pass."""
        rays, poses = batch.weights.shape
        log_dt = torch.log(batch.exposure_s)
        value_fn = self.variant.imaging.sample_values(self.crf, log_dt, poses)
        passes = self.renderer(
            batch.origins.reshape(-1, 3),
            batch.directions.reshape(-1, 3),
            self.near,
            self.far,
            value_fn,
            generator,
        )
        return [
            self._predict(
                batch, rendered.values.reshape(rays, poses, -1), log_dt, rendered.num_samples
            )
            for rendered in passes
        ]

    def _predict(
        self, batch: RayBatch, values: torch.Tensor, log_dt: torch.Tensor, num_samples: int
    ) -> Prediction:
        ldr, log_radiance = self.variant.imaging.blurry_ldr(self.crf, batch, values, log_dt)
        counts = None
        if self.event_crf is not None:
            counts = self.event_crf(log_radiance, batch.mix, batch.exposure_s, batch.subframes)
        return Prediction(ldr, counts, log_radiance, num_samples)

    def span_changes(
        self, spans: SpanBatch, generator: torch.Generator | None = None
    ) -> list[torch.Tensor]:
        """``(R,)`` predicted change of each span in units of the threshold, one per pass.

        The change is the ln radiance the event pixel sees at the span's last point less that at
        its first; the points lie frames apart, where the pixel's low-pass has long settled.
        """
        rays = spans.origins.shape[0]
        passes = self.renderer(
            spans.origins.reshape(-1, 3),
            spans.directions.reshape(-1, 3),
            self.near,
            self.far,
            None,
            generator,
        )
        changes = []
        for rendered in passes:
            pixel = self.event_crf.pixel_log_radiance(
                rendered.values.reshape(rays, 2, -1), spans.mix
            )
            changes.append((pixel[:, 1] - pixel[:, 0]) / self.event_crf.threshold)
        return changes

    def render_log_radiance(self, origins: torch.Tensor, directions: torch.Tensor) -> torch.Tensor:
        """``(R, 3)`` rendered log radiance of sharp rays (last pass), no jitter."""
        return self.renderer(origins, directions, self.near, self.far)[-1].values

    def hdr_from_log(self, log_radiance: torch.Tensor) -> torch.Tensor:
        """Linear HDR radiance ``(R, 3)``; the LDR-field variant's output is its LDR image."""
        return self.variant.imaging.hdr(log_radiance)

    def ldr_from_log(self, log_radiance: torch.Tensor, exposure_s: float) -> torch.Tensor:
        """LDR ``(R, 3)`` at a new exposure through the learned per-pixel response.

        The 3-D point CRF is applied here after rendering (an approximation for that variant);
        the LDR field scales its output by the exposure ratio and clips.
        """
        return self.variant.imaging.ldr(
            self.crf, log_radiance, exposure_s, self.reference_exposure_s
        )

    def ldr_images(self, log_radiance: torch.Tensor, exposures_s) -> list[torch.Tensor]:
        """:meth:`ldr_from_log` at each exposure, for whole images (a tabulated response)."""
        return self.variant.imaging.ldr_images(
            self.crf, log_radiance, exposures_s, self.reference_exposure_s
        )
