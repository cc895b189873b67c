"""``seecap fit``: calibration and poses if missing, See-NeRF training, renders and scores."""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

from davis_io.session import seconds_argument
from seenerf.cli.options import add_dataclass_options, dataclass_values
from seenerf.cli.progress import TrainingBar
from seenerf.errors import OptionError
from seenerf.model.config import FIELD_BOUNDS, GROUPS, FitConfig

__all__ = ["FLAGS", "HELP", "add_arguments", "config_from_options", "run"]

HELP = (
    "fit See-NeRF to a session (sensor calibration and poses if missing): sharp HDR renders, "
    "LDR brackets, scores"
)

FLAGS = {
    "register_test_views": "--no-registration",
    "dead_time": "--no-dead-time",
    "frame_noise": "--no-frame-noise",
}
"""Option strings that differ from the ones derived from :class:`FitConfig`'s field names."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments: session and run, then an option group per configuration group.

    Each field of a group of :class:`FitConfig` (:data:`GROUPS`) is one option.
    """
    parser.add_argument(
        "session", type=Path, nargs="+", help="session folder(s): in turn, or at once with --ray"
    )
    parser.add_argument("--run", default=None, help="run folder name under session/fit/")
    parser.add_argument("--fresh", action="store_true", help="start over instead of resuming")
    parser.add_argument(
        "--config",
        type=Path,
        metavar="CONFIG_JSON",
        help="fit again with the configuration a run saved (its config.json); fit options "
        "given beside it replace its values",
    )
    parser.add_argument(
        "--ray",
        metavar="local|auto|ADDRESS",
        help="fit each session as a Ray task: 'local' starts Ray on this machine, 'auto' joins "
        "the cluster `ray start` made here, ADDRESS is a cluster's head; sessions must be on "
        "storage every node sees (needs the cluster extra)",
    )
    parser.add_argument(
        "--quiet", action="store_true", help="no progress bar or lines: the result only"
    )
    parser.add_argument(
        "--camera-calibration",
        type=Path,
        metavar="FILE",
        help="the camera's lens: DV's or OpenCV's calibration (XML or YAML), COLMAP's "
        "cameras.txt or JSON with fx, fy, cx, cy and optionally k1, k2, p1, p2, k3; poses are "
        "estimated with it held fixed, and rays and renders follow it (default: COLMAP "
        "estimates a pinhole)",
    )
    seconds = seconds_argument("--time-budget", FIELD_BOUNDS["time_budget_s"])
    for name, group in GROUPS.items():
        title = inspect.getdoc(group).splitlines()[0]
        options = parser.add_argument_group(f"{name} options", title)
        add_dataclass_options(options, group, seconds, flags=FLAGS, bounds=FIELD_BOUNDS)


def config_from_options(args: argparse.Namespace) -> FitConfig:
    """The configuration the parsed options state."""
    return FitConfig(
        **{name: group(**dataclass_values(group, args)) for name, group in GROUPS.items()}
    )


def run(args: argparse.Namespace) -> int:
    """Make each session ready and fit it; print the scores (a table for several); 0 if all fit."""
    from davis_io.session.folder import plain_name
    from seenerf.model.config import load_config

    if args.run is not None:
        plain_name(args.run, "--run")
    config = config_from_options(args)
    if args.config is not None:
        # The saved run's configuration, with the options given beside it on top.
        defaults = FitConfig().options()
        given = {name: value for name, value in config.options().items() if value != defaults[name]}
        config = load_config(args.config).replaced(**given)
    if args.ray is not None and args.camera_calibration is not None:
        raise OptionError(
            "--camera-calibration with --ray: estimate each session's poses first with "
            "`seecap poses SESSION --camera-calibration FILE`, then fit them with --ray"
        )
    if args.ray is None and len(args.session) == 1:
        return _fit_here(args.session[0], config, args)
    if args.ray is None:
        fits = [_fit_in_turn(session, config, args) for session in args.session]
    else:
        fits = _fit_on_ray(config, args)
    return _report(fits)


def _fit_here(session: Path, config: FitConfig, args: argparse.Namespace) -> int:
    """One session in this process; a failure propagates to the CLI's one-line report."""
    from seenerf.cli.sessions import prepare_and_fit
    from seenerf.eval.scores import format_scores

    bar = TrainingBar(args.quiet)
    try:
        result = prepare_and_fit(
            session,
            config,
            run_name=args.run,
            fresh=args.fresh,
            log=bar.line,
            camera_calibration=args.camera_calibration,
            on_step=lambda trainer: bar.update(trainer.training_progress()),
        )
    finally:
        bar.close()
    print(f"run: {result.run_dir}")
    print(format_scores(result.metrics))
    return 0


def _fit_in_turn(session: Path, config: FitConfig, args: argparse.Namespace):
    """One of several sessions in this process; its failure is kept, the next one goes on."""
    from seenerf.cli.sessions import fit_kept_apart

    bar = TrainingBar(args.quiet, label=str(session))
    try:
        return fit_kept_apart(
            session,
            config,
            run_name=args.run,
            fresh=args.fresh,
            log=lambda text: bar.line(f"{session}: {text}"),
            camera_calibration=args.camera_calibration,
            on_step=lambda trainer: bar.update(trainer.training_progress()),
        )
    finally:
        bar.close()


def _fit_on_ray(config: FitConfig, args: argparse.Namespace):
    """Every session as a Ray task, with one progress bar per session."""
    from seenerf.cli.cluster import fit_on_ray

    bars = [
        TrainingBar(args.quiet, label=str(session), position=index)
        for index, session in enumerate(args.session)
    ]
    try:
        return fit_on_ray(
            args.session,
            config,
            address=args.ray,
            run_name=args.run,
            fresh=args.fresh,
            on_line=lambda index, text: bars[index].line(f"{args.session[index]}: {text}"),
            on_progress=lambda index, progress: bars[index].update(progress),
        )
    finally:
        for bar in bars:
            bar.close()


def _report(fits) -> int:
    """The scores of one fit, or a table of several; one error line per failed session."""
    from seenerf.cli.sessions import score_table
    from seenerf.eval.scores import format_scores

    if len(fits) == 1 and not fits[0].error:
        print(f"run: {fits[0].run_dir}")
        print(format_scores(fits[0].metrics))
    elif len(fits) > 1:
        print(score_table(fits))
    for fit in fits:
        if fit.error:
            print(f"seecap: error: fit: {fit.session}: {fit.error}", file=sys.stderr)
    return 1 if any(fit.error for fit in fits) else 0
