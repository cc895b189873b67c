"""The resolved configuration of one fit, in groups, saved with every run (``config.json``).

Each group is a frozen dataclass whose fields are ``seecap fit``'s options (one option group of
``--help`` each), named once across the groups. A field that defaults to None takes its value
from elsewhere, as its entry says: the preset's (``steps``, ``batch_pixels``, ...), the
session's (``bins``), the calibration's (``threshold``) or the machine's (``threads``).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from pathlib import Path

from davis_io.session import Bounds, output_errors
from davis_io.session.defaults import SEED, THRESHOLD
from seenerf.errors import ConfigError, OptionError
from seenerf.model.presets import DEFAULT_PRESET, PRESETS

__all__ = [
    "DEFAULT_VARIANT",
    "FIELD_BOUNDS",
    "GROUPS",
    "DataConfig",
    "FitConfig",
    "ModelConfig",
    "OutputConfig",
    "ScheduleConfig",
    "SensorConfig",
    "load_config",
    "option_name",
    "save_config",
]

DEFAULT_VARIANT = "full"
"""The paper's method: what a fit runs unless told otherwise and what benchmarks measure."""


@dataclass(frozen=True)
class ModelConfig:
    """What is fitted: the field's preset, the variant and its loss.

    Attributes:
        preset: training preset: ``fast``, ``balanced`` or ``paper`` (the published 8x256 MLP).
        variant: model variant: ``full`` (the paper's method) or a comparison (``no-events``,
            ``base``, ``oracle``, ...; an unknown name lists them).
        event_weight: lambda of eq. 15, the event loss's weight (default: the preset's; the
            published 0.005 for ``paper``, 0.001 for ``fast`` and ``balanced``).
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
    event_weight: float | None = None
    subframes: int = 1
    refine_poses: bool = False


@dataclass(frozen=True)
class SensorConfig:
    """The camera's model: its response, its event thresholds, filter and dead time.

    Attributes:
        response: the RGB response of the variants that learn one: ``auto`` (linear above the
            black level and clipped, when the calibration measured the frames linear as a raw
            DAVIS frame is; else learned), ``learned`` (always the response MLPs) or
            ``monotone`` (a rising S-curve of three numbers per channel instead of the MLPs).
        anchor_weight: weight of the CRF anchor term.
        anchor_log_exposure: ln(radiance x s) of the CRF anchor point.
        anchor_value: LDR value of the CRF at the anchor point.
        threshold: DVS contrast threshold Theta in log units for ON, OFF and every pixel,
            overriding the ones measured from the recording (default: measured; the events
            alone set the field's log contrast).
        cutoff_hz: photoreceptor cut-off frequency of the delay filter, unless the sensor's
            values state it.
        low_pass: reading of the delay filter: ``reference`` (first order on log radiance) or
            ``paper`` (second order on linear radiance).
        dead_time: use the pixels' measured dead time (refractory period): predicted events
            of a pixel are limited to one per dead time, the rest owed to later bins, and
            counts are compared between the latent points where the pixel was not firing at
            that limit (:mod:`davis_io.settled`); off: every bin alone, unlimited.
        frame_noise: on linear frames whose noise the calibration measured, compare frame
            values on a scale where that noise is even (each pixel weighed by the inverse of its
            noise variance, so the shadows count); off: plain squared errors.
    """

    response: str = "auto"
    anchor_weight: float = 0.5
    anchor_log_exposure: float = 0.0
    anchor_value: float = 0.5
    threshold: float | None = None
    cutoff_hz: float = 150.0
    low_pass: str = "reference"
    dead_time: bool = True
    frame_noise: bool = True


@dataclass(frozen=True)
class DataConfig:
    """What each step trains on.

    Attributes:
        bins: event bins per exposure b (default: the session's).
        batch_pixels: blurry pixels per step (default: the preset's).
        event_share: fraction of each batch drawn among pixels with events.
        span_share: spans per step, as a share of the batch's pixels: a pixel seen at latent
            points of two frames, whose change the events between them give (0: none).
        span_reach: the most frames apart a span's two points lie.
        lone_exposure_spans: frames alone in their stretch of the event stream (recorded view
            by view, or between gaps) compare their events over the whole exposure, first
            latent point to last, as well as bin by bin. With no events between frames to
            correct them, a pose error of a fraction of a pixel moves an edge's crossing into
            another bin, and bin by bin alone the fit hedges with a fraction of the edge's
            contrast.
        validation_share: fraction of training pixels held out for the progress PSNR.
    """

    bins: int | None = None
    batch_pixels: int | None = None
    event_share: float = 0.5
    span_share: float = 0.5
    span_reach: int = 8
    lone_exposure_spans: bool = True
    validation_share: float = 0.01


@dataclass(frozen=True)
class ScheduleConfig:
    """How long and where training runs.

    Attributes:
        steps: training steps (default: the preset's count, or none with a time budget).
        time_budget_s: the whole fit's time, calibration, poses, training and the final renders
            together (default: none; a duration on the command line: ``10m``, ``600s``).
        warm_steps: CRF warm-start steps (default: the preset's, the reference's 500).
        seed: seed of every random draw.
        device: ``auto`` (CUDA when present), ``cpu`` or ``cuda``.
        threads: CPU threads of each pool: torch's, numpy's BLAS, OpenCV's, the calibration's
            and COLMAP's (default: ``seecap fit`` takes the cores other work leaves free, one
            thread each).
    """

    steps: int | None = None
    time_budget_s: float | None = None
    warm_steps: int | None = None
    seed: int = 0
    device: str = "auto"
    threads: int | None = None


@dataclass(frozen=True)
class OutputConfig:
    """What a fit renders and scores after training.

    Attributes:
        exposures_s: exposures of the rendered LDR brackets (default: the truth's or the
            paper's five).
        register_test_views: before scoring a fit made from estimated poses, refine each
            held-out pose against its image (the scores at the similarity-mapped poses are kept
            too).
    """

    exposures_s: tuple[float, ...] = ()
    register_test_views: bool = True


GROUPS: dict[str, type] = {
    "model": ModelConfig,
    "sensor": SensorConfig,
    "data": DataConfig,
    "schedule": ScheduleConfig,
    "output": OutputConfig,
}
"""Every group of :class:`FitConfig` by its attribute name, in ``--help``'s order."""

_GROUP_OF = {
    option.name: group for group, cls in GROUPS.items() for option in dataclasses.fields(cls)
}
"""The group of each option by name (a name is in one group only)."""

_LEFT_OPEN = {
    option.name
    for cls in GROUPS.values()
    for option in dataclasses.fields(cls)
    if option.default is None
}
"""The options that None leaves to the preset, the session, the calibration or the machine."""

_WEIGHT = Bounds(0.0, 1e3)
FIELD_BOUNDS: dict[str, Bounds] = {
    "event_weight": _WEIGHT,
    "subframes": Bounds(1, 64, "poses per bin", integer=True),
    "anchor_weight": _WEIGHT,
    "anchor_log_exposure": Bounds(-50.0, 50.0, "ln(radiance x s)"),
    "anchor_value": Bounds(0.0, 1.0, low_open=True, high_open=True),
    "threshold": THRESHOLD,
    "cutoff_hz": Bounds(0.0, 1e6, "Hz", low_open=True),
    "bins": Bounds(1, 64, "bins", integer=True),
    "batch_pixels": Bounds(1, 1_000_000, "pixels", integer=True),
    "event_share": Bounds(0.0, 1.0),
    "span_share": Bounds(0.0, 4.0),
    "span_reach": Bounds(0, 100_000, "frames", integer=True),
    "validation_share": Bounds(0.0, 0.5, high_open=True),
    "steps": Bounds(1, 10_000_000, "steps", integer=True),
    "time_budget_s": Bounds(0.0, 30 * 86_400.0, "s", low_open=True),
    "warm_steps": Bounds(0, 1_000_000, "steps", integer=True),
    "seed": SEED,
    "threads": Bounds(1, 1024, "threads", integer=True),
}
"""The values each numeric option takes when it is given (None leaves it to the preset, the
session, the calibration or the machine), checked for options and a ``config.json`` alike."""

_EXPOSURE = Bounds(1e-6, 30 * 86_400.0, "s")
"""An exposure of the rendered brackets."""

_CHOICES: dict[str, tuple[str, ...]] = {
    "response": ("auto", "learned", "monotone"),
    "device": ("auto", "cpu", "cuda"),
}

_FLAT_SENTINELS = {
    "steps": 0,
    "time_budget_s": 0.0,
    "warm_steps": -1,
    "event_weight": 0.0,
    "threshold": 0.0,
    "bins": 0,
    "batch_pixels": 0,
    "threads": 0,
}
"""The values that meant "not given" in the flat ``config.json`` of runs made before the
groups: read back as None."""


@dataclass(frozen=True)
class FitConfig:
    """How to fit one session: its options in groups (:data:`GROUPS`).

    Attributes:
        model: what is fitted.
        sensor: the camera's model.
        data: what each step trains on.
        schedule: how long and where training runs.
        output: what is rendered and scored.
    """

    model: ModelConfig = field(default_factory=ModelConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    data: DataConfig = field(default_factory=DataConfig)
    schedule: ScheduleConfig = field(default_factory=ScheduleConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    def __post_init__(self):
        """Check names and ranges: a configuration that exists is valid.

        Raises:
            OptionError: naming the option, the value and the accepted values.
        """
        # Imported here, not above: the variants build torch modules, and FitConfig is read
        # (without torch) by every ``seecap`` verb's parser, fit's options coming from its fields.
        from seenerf.model.variants import LOW_PASS_READINGS, VARIANTS

        options = self.options()
        for name, table in (
            ("preset", PRESETS),
            ("variant", VARIANTS),
            ("low_pass", LOW_PASS_READINGS),
            *_CHOICES.items(),
        ):
            if options[name] not in table:
                raise OptionError(
                    f"{name} {options[name]!r} is unknown; choose one of: {', '.join(table)}"
                )
        problems = [
            bounds.problem(option_name(name), options[name])
            for name, bounds in FIELD_BOUNDS.items()
            if options[name] is not None or name not in _LEFT_OPEN
        ] + [_EXPOSURE.problem("--exposures", exposure) for exposure in options["exposures_s"]]
        for problem in problems:
            if problem is not None:
                raise OptionError(problem)
        for name in ("dead_time", "frame_noise", "register_test_views", "refine_poses"):
            if not isinstance(options[name], bool):
                raise OptionError(f"{name} {options[name]!r} must be true or false")

    @classmethod
    def of(cls, **options) -> FitConfig:
        """The default configuration with the options named, each in its group.

        Raises:
            OptionError: an option no group has.
        """
        return cls().replaced(**options)

    def replaced(self, **options) -> FitConfig:
        """This configuration with the options named replaced, each in its group.

        Raises:
            OptionError: an option no group has.
        """
        unknown = sorted(set(options) - set(_GROUP_OF))
        if unknown:
            raise OptionError(f"no fit option is called {', '.join(unknown)}")
        groups = {
            group: dataclasses.replace(
                getattr(self, group),
                **{name: value for name, value in options.items() if _GROUP_OF[name] == group},
            )
            for group in GROUPS
        }
        return dataclasses.replace(self, **groups)

    def options(self) -> dict:
        """Every option by name, the groups flattened."""
        return {
            name: value
            for group in GROUPS
            for name, value in dataclasses.asdict(getattr(self, group)).items()
        }

    def training_key(self) -> dict:
        """What a checkpoint must agree with to be resumed.

        The model, sensor and data groups and the seed; not the rest of the schedule (steps,
        budget, device, threads) or the outputs.
        """
        return {
            "model": dataclasses.asdict(self.model),
            "sensor": dataclasses.asdict(self.sensor),
            "data": dataclasses.asdict(self.data),
            "seed": self.schedule.seed,
        }


def option_name(field_name: str) -> str:
    """The command-line option of a field: ``time_budget_s`` -> ``--time-budget``."""
    return "--" + field_name.removesuffix("_s").replace("_", "-")


def save_config(config: FitConfig, path: Path, extra: dict | None = None) -> None:
    """Write the config (and resolved extras such as the field size) as JSON."""
    payload = {"config": dataclasses.asdict(config), **(extra or {})}
    with output_errors(path):
        path.write_text(json.dumps(payload, indent=2, default=str) + "\n")


def load_config(path: Path) -> FitConfig:
    """Read a ``config.json`` written by :func:`save_config` (or, flat, before the groups).

    Raises:
        ConfigError: the file is missing or not a seecap fit config.
        OptionError: a value out of range, naming the file.
    """
    try:
        saved = json.loads(Path(path).read_text())["config"]
        if "model" in saved:
            options = {name: value for group in GROUPS for name, value in saved[group].items()}
        else:
            options = {
                name: None if _FLAT_SENTINELS.get(name, ...) == value else value
                for name, value in saved.items()
            }
        options["exposures_s"] = tuple(options.get("exposures_s", ()))
        return FitConfig.of(**options)
    except OptionError as error:
        raise OptionError(f"{path}: {error}") from None
    except (OSError, KeyError, TypeError, AttributeError, json.JSONDecodeError) as error:
        raise ConfigError(
            f"{path}: not a readable fit config ({error}); re-run seecap fit"
        ) from error
