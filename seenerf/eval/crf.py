"""The learned RGB response against the true one: its curve on the truth's axis, plot and error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from seenerf.data.arrays import TrainingData
from seenerf.eval.metrics import align_channel_scale
from seenerf.eval.plots import crf_plot
from seenerf.eval.views import RenderedViews
from seenerf.model.model import SeeNerfModel
from seenerf.sensors.rgb_crf import TabulatedCrf

__all__ = ["crf_error", "learned_crf", "plot_crf"]


def learned_crf(
    model: SeeNerfModel, data: TrainingData, views: RenderedViews
) -> tuple[np.ndarray, np.ndarray] | None:
    """The learned response ``(x, (N, 3) values)`` on the truth's ln(radiance x s) axis.

    The model's radiance is known up to the CRF anchor; its per-channel HDR scale against the
    truth (when scored) shifts the curve onto the truth's axis. None without a learned CRF.
    """
    if model.crf is None or isinstance(model.crf, TabulatedCrf):
        return None
    log_exposure = np.linspace(-8.0, 6.0, 141, dtype=np.float32)
    with torch.no_grad():
        values = model.crf(torch.as_tensor(log_exposure)[:, None].expand(-1, 3)).numpy()
    shift = 0.0
    if data.test is not None and views.hdr:
        scale = align_channel_scale(np.stack(views.hdr), data.test.hdr)
        shift = float(np.log(np.mean(scale)))
    return log_exposure + shift, values


def _true_crf(data: TrainingData) -> tuple[np.ndarray, np.ndarray] | None:
    truth = data.truth
    if truth is None or not len(truth.crf_value):
        return None
    return np.asarray(truth.crf_log_exposure), np.asarray(truth.crf_value)


def _channels_in_use(data: TrainingData) -> tuple[int, ...]:
    """The response curves the sensor's pixels go through (a monochrome sensor: the first)."""
    return tuple(int(c) for c in np.unique(data.channel))


def plot_crf(model: SeeNerfModel, data: TrainingData, views: RenderedViews, path: Path) -> None:
    """The learned response beside the true one, when the model has one: the curves in use."""
    learned = learned_crf(model, data, views)
    if learned is not None:
        crf_plot(path, learned, _true_crf(data), _channels_in_use(data))


def crf_error(model: SeeNerfModel, data: TrainingData, views: RenderedViews) -> dict | None:
    """RMS and largest difference of the learned and the true response, per channel in use.

    Only the curves the sensor's pixels go through are compared (a monochrome sensor uses the
    first; the others are never trained), where the true response is between 0.01 and 0.99
    (below and above, every curve clips) and the learned curve was evaluated. Returns
    ``{"channels": [...], "rms": [...], "max": [...]}``, or None without a CRF or a true one.
    """
    learned, true = learned_crf(model, data, views), _true_crf(data)
    if learned is None or true is None:
        return None
    (x, values), (true_x, true_values) = learned, true
    inside = (true_x >= x[0]) & (true_x <= x[-1])
    channels = list(_channels_in_use(data))
    rms, largest = [], []
    for channel in channels:
        reference = true_values[:, min(channel, true_values.shape[1] - 1)]
        keep = inside & (reference > 0.01) & (reference < 0.99)
        difference = np.interp(true_x[keep], x, values[:, channel]) - reference[keep]
        rms.append(float(np.sqrt(np.mean(difference**2))) if keep.any() else float("nan"))
        largest.append(float(np.max(np.abs(difference))) if keep.any() else float("nan"))
    return {"channels": channels, "rms": rms, "max": largest}
