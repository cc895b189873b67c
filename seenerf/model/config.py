"""The resolved configuration of one fit, saved with every run (``config.json``)."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from davis_io.session import Bounds, output_errors
from davis_io.session.defaults import SEED, THRESHOLD
from seenerf.errors import ConfigError, OptionError
from seenerf.model.presets import DEFAULT_PRESET, PRESETS

__all__ = ["DEFAULT_VARIANT", "FIELD_BOUNDS", "FitConfig", "load_config", "save_config"]

DEFAULT_VARIANT = "full"
"""The paper's method: what a fit runs unless told otherwise and what benchmarks measure."""

_WEIGHT = Bounds(0.0, 1e3)
FIELD_BOUNDS: dict[str, Bounds] = {
    "steps": Bounds(0, 10_000_000, "steps", integer=True),
    "time_budget_s": Bounds(0.0, 30 * 86_400.0, "s"),
    "seed": SEED,
    "bins": Bounds(0, 64, "bins", integer=True),
    "event_weight": _WEIGHT,
    "anchor_weight": _WEIGHT,
    "anchor_log_exposure": Bounds(-50.0, 50.0, "ln(radiance x s)"),
    "anchor_value": Bounds(0.0, 1.0, low_open=True, high_open=True),
    "threshold": Bounds(0.0, THRESHOLD.high, THRESHOLD.unit),
    "cutoff_hz": Bounds(0.0, 1e6, "Hz", low_open=True),
    "event_share": Bounds(0.0, 1.0),
    "validation_share": Bounds(0.0, 0.5, high_open=True),
    "threads": Bounds(0, 1024, "threads", integer=True),
    "batch_pixels": Bounds(0, 1_000_000, "pixels", integer=True),
    "warm_steps": Bounds(-1, 1_000_000, "steps", integer=True),
    "subframes": Bounds(1, 64, "poses per bin", integer=True),
}
"""The values each numeric field of :class:`FitConfig` takes (0 and -1 mean the preset's where
the field says so), checked for options and for a ``config.json`` read back alike."""

_EXPOSURE = Bounds(1e-6, 30 * 86_400.0, "s")
"""An exposure of the rendered brackets."""

_CHOICES: dict[str, tuple[str, ...]] = {
    "response": ("auto", "learned"),
    "device": ("auto", "cpu", "cuda"),
}


@dataclass
class FitConfig:
    """How to fit one session. Field docstrings double as CLI help.

    Attributes:
        preset: training preset: ``fast``, ``balanced`` or ``paper`` (the published 8x256 MLP).
        variant: model variant: ``full`` (the paper's method) or a comparison (``no-events``,
            ``base``, ``oracle``, ...; an unknown name lists them).
        steps: training steps; 0 uses the preset's count.
        time_budget_s: stop training after this many seconds, poses included (0 = no budget;
            a duration on the command line: ``10m``, ``600s``).
        device: ``auto`` (CUDA when present), ``cpu`` or ``cuda``.
        seed: seed of every random draw.
        bins: event bins per exposure b; 0 uses the session's.
        low_pass: reading of the delay filter: ``reference`` (first order on log radiance) or
            ``paper`` (second order on linear radiance).
        event_weight: lambda of eq. 15, the event loss's weight (0: the preset's; the
            published 0.005 for ``paper``, 0.001 for ``fast`` and ``balanced``).
        anchor_weight: weight of the CRF anchor term.
        anchor_log_exposure: ln(radiance x s) of the CRF anchor point.
        anchor_value: LDR value of the CRF at the anchor point.
        response: the RGB response of the variants that learn one: ``auto`` (linear above the
            black level and clipped, when the calibration measured the frames linear as a raw
            DAVIS frame is; else learned) or ``learned`` (always the response MLPs).
        threshold: DVS contrast threshold Theta in log units for ON, OFF and every pixel,
            overriding the ones measured from the recording (0: measured; the events alone set
            the field's log contrast).
        cutoff_hz: photoreceptor cut-off frequency of the delay filter, unless the sensor's
            values state it.
        dead_time: use the pixels' measured dead time (refractory period): predicted events
            of a pixel are limited to one per dead time, the rest owed to later bins, and
            counts are compared between the latent points where the pixel was not firing at
            that limit (:mod:`davis_io.settled`); off: every bin alone, unlimited.
        frame_noise: on linear frames whose noise the calibration measured, compare frame
            values on a scale where that noise is even (each pixel weighed by the inverse of its
            noise variance, so the shadows count); off: plain squared errors.
        event_share: fraction of each batch drawn among pixels with events.
        validation_share: fraction of training pixels held out for the progress PSNR.
        exposures_s: exposures of the rendered LDR brackets (empty: the truth's or the
            paper's five).
        threads: CPU threads of each pool: torch's, numpy's BLAS, OpenCV's, the calibration's
            and COLMAP's (0: ``seecap fit`` takes the cores other work leaves free, one thread
            each).
        batch_pixels: blurry pixels per step (0: the preset's).
        warm_steps: CRF warm-start steps (-1: the preset's, the reference's 500).
        register_test_views: before scoring a fit made from estimated poses, refine each
            held-out pose against its image (the scores at the similarity-mapped poses are kept
            too).
        subframes: poses per event bin in the exposure integral, interpolated between the
            latent poses (:mod:`seenerf.data.subframes`); 1 is the published b+1 latent poses,
            more is for motion of many pixels per bin (the event model then follows each pixel
            through them).
        refine_poses: learn a small rotation and translation of each training view's poses
            with the field (:mod:`seenerf.model.pose_correction`); the test poses are then
            mapped from the corrected cameras.
    """

    preset: str = DEFAULT_PRESET
    variant: str = DEFAULT_VARIANT
    steps: int = 0
    time_budget_s: float = 0.0
    device: str = "auto"
    seed: int = 0
    bins: int = 0
    low_pass: str = "reference"
    event_weight: float = 0.0
    anchor_weight: float = 0.5
    anchor_log_exposure: float = 0.0
    anchor_value: float = 0.5
    response: str = "auto"
    threshold: float = 0.0
    cutoff_hz: float = 150.0
    dead_time: bool = True
    frame_noise: bool = True
    event_share: float = 0.5
    validation_share: float = 0.01
    exposures_s: tuple[float, ...] = ()
    threads: int = 0
    batch_pixels: int = 0
    warm_steps: int = -1
    register_test_views: bool = True
    subframes: int = 1
    refine_poses: bool = False

    def validate(self) -> FitConfig:
        """Check names and ranges; return self.

        Raises:
            ConfigError: naming the field, the value and the accepted values.
        """
        # Imported here, not above: the variants build torch modules, and FitConfig is read
        # (without torch) by every ``seecap`` verb's parser, fit's options coming from its fields.
        from seenerf.model.variants import LOW_PASS_READINGS, VARIANTS

        for name, table in (
            ("preset", PRESETS),
            ("variant", VARIANTS),
            ("low_pass", LOW_PASS_READINGS),
            *_CHOICES.items(),
        ):
            if getattr(self, name) not in table:
                raise OptionError(
                    f"{name} {getattr(self, name)!r} is unknown; choose one of: {', '.join(table)}"
                )
        problems = [
            bounds.problem(option_name(name), getattr(self, name))
            for name, bounds in FIELD_BOUNDS.items()
        ] + [_EXPOSURE.problem("--exposures", exposure) for exposure in self.exposures_s]
        for problem in problems:
            if problem is not None:
                raise OptionError(problem)
        for name in ("dead_time", "frame_noise", "register_test_views", "refine_poses"):
            if not isinstance(getattr(self, name), bool):
                raise OptionError(f"{name} {getattr(self, name)!r} must be true or false")
        return self

    def training_key(self) -> dict:
        """The fields a checkpoint must agree with to be resumed (not budget or steps)."""
        keep = (
            "preset",
            "variant",
            "seed",
            "bins",
            "low_pass",
            "event_weight",
            "anchor_weight",
            "anchor_log_exposure",
            "anchor_value",
            "response",
            "threshold",
            "cutoff_hz",
            "dead_time",
            "frame_noise",
            "event_share",
            "batch_pixels",
            "subframes",
            "refine_poses",
        )
        return {name: getattr(self, name) for name in keep}


def option_name(field_name: str) -> str:
    """The command-line option of a field: ``time_budget_s`` -> ``--time-budget``."""
    return "--" + field_name.removesuffix("_s").replace("_", "-")


def save_config(config: FitConfig, path: Path, extra: dict | None = None) -> None:
    """Write the config (and resolved extras such as the field size) as JSON."""
    payload = {"config": dataclasses.asdict(config), **(extra or {})}
    with output_errors(path):
        path.write_text(json.dumps(payload, indent=2, default=str) + "\n")


def load_config(path: Path) -> FitConfig:
    """Read a ``config.json`` written by :func:`save_config`.

    Raises:
        ConfigError: the file is missing or not a seecap fit config.
    """
    try:
        values = json.loads(Path(path).read_text())["config"]
        values["exposures_s"] = tuple(values.get("exposures_s", ()))
        return FitConfig(**values).validate()
    except OptionError as error:
        raise OptionError(f"{path}: {error}") from None
    except (OSError, KeyError, TypeError, json.JSONDecodeError) as error:
        raise ConfigError(
            f"{path}: not a readable fit config ({error}); re-run seecap fit"
        ) from error
