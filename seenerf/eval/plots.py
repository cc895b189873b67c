"""Figures of a fit: its response curves beside the true ones, and its training curves."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from davis_io.session import output_errors

__all__ = ["camera_path_plot", "crf_plot", "training_curves"]

_CHANNELS = (("R", "tab:red"), ("G", "tab:green"), ("B", "tab:blue"))


def _figure(size=(6.4, 4.2)):
    import matplotlib

    matplotlib.use("Agg")  # files only, never a window
    from matplotlib import pyplot

    return pyplot, *pyplot.subplots(figsize=size, dpi=100)


def _save(pyplot, figure, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    try:
        with output_errors(path):
            figure.savefig(path)
    finally:
        pyplot.close(figure)


def crf_plot(
    path: Path,
    learned: tuple[np.ndarray, np.ndarray],
    true: tuple[np.ndarray, np.ndarray] | None,
    channels: tuple[int, ...] = (0, 1, 2),
) -> None:
    """Response curves: LDR value against ln(radiance x seconds), learned solid, true dashed.

    Args:
        path: PNG to write.
        learned: ``(K,)`` log exposures and ``(K, 3)`` learned LDR values.
        true: the same for the true response (``(K, 1)`` for a monochrome one), or None.
        channels: the curves the sensor's pixels go through; one alone is drawn grey.
    """
    pyplot, figure, axes = _figure()
    for channel in channels:
        name, colour = _CHANNELS[channel] if len(channels) > 1 else ("grey", "0.3")
        axes.plot(learned[0], learned[1][:, channel], color=colour, label=f"{name} learned")
        if true is not None:
            curve = true[1][:, min(channel, true[1].shape[1] - 1)]
            axes.plot(true[0], curve, color=colour, linestyle="--", label=f"{name} true")
    axes.set_xlabel("ln(radiance × exposure in s)")
    axes.set_ylabel("LDR value")
    axes.set_ylim(-0.02, 1.02)
    axes.grid(alpha=0.3)
    axes.legend(fontsize="small")
    _save(pyplot, figure, path)


def training_curves(path: Path, history: list[dict]) -> None:
    """Held-out PSNR and the LDR and event losses against the training step."""
    if not history:
        return
    steps = np.array([record["step"] for record in history])
    pyplot, figure, axes = _figure()
    axes.plot(steps, [r.get("val_psnr", np.nan) for r in history], color="black", label="PSNR")
    axes.set_xlabel("training step")
    axes.set_ylabel("held-out PSNR of the blurry frames, dB")
    losses = axes.twinx()
    for term, colour in (("ldr", "tab:blue"), ("events", "tab:orange")):
        values = np.array([r.get(term, np.nan) for r in history], float)
        if np.isfinite(values).any() and np.nanmax(values) > 0:
            losses.semilogy(steps, values, color=colour, alpha=0.8, label=f"{term} loss")
    losses.set_ylabel("loss")
    lines = axes.get_legend_handles_labels()
    more = losses.get_legend_handles_labels()
    axes.legend(lines[0] + more[0], lines[1] + more[1], fontsize="small", loc="center right")
    axes.grid(alpha=0.3)
    _save(pyplot, figure, path)


def camera_path_plot(path: Path, centres: np.ndarray, registered: np.ndarray) -> None:
    """The camera centres ``(N, 3)`` in time order, seen along the path's thinnest direction.

    Registered latent poses are dots on the line; those COLMAP left out (interpolated) rings.
    """
    centres = np.asarray(centres, np.float64).reshape(-1, 3)
    pyplot, figure, axes = _figure((5.0, 4.2))
    if len(centres):
        mean = centres.mean(axis=0)
        _, _, directions = np.linalg.svd(centres - mean, full_matrices=False)
        flat = (centres - mean) @ directions[:2].T
        registered = np.asarray(registered, bool).reshape(-1)
        axes.plot(flat[:, 0], flat[:, 1], color="0.6", linewidth=0.8)
        axes.scatter(*flat[registered].T, s=8, color="tab:blue", label="registered")
        if (~registered).any():
            axes.scatter(
                *flat[~registered].T,
                s=14,
                facecolors="none",
                edgecolors="tab:red",
                label="interpolated",
            )
        axes.scatter(*flat[0], s=40, marker="^", color="black", label="start")
        axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("along the path's widest direction")
    axes.set_ylabel("across it")
    axes.grid(alpha=0.3)
    axes.legend(fontsize="small")
    _save(pyplot, figure, path)
