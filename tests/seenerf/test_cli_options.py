import argparse
import dataclasses
from dataclasses import dataclass

from seenerf.cli import fit_verb
from seenerf.cli.options import (
    add_dataclass_options,
    attribute_docs,
    dataclass_values,
    plain_text,
)
from seenerf.model.config import FitConfig


def test_attribute_docs_reads_entries_and_their_continuations():
    doc = """Something.

    Longer text.

    Attributes:
        alpha: first line
            goes on here.
        beta (int): typed entry.
        gamma: ``x`` and :mod:`a.b`.

    Raises:
        ValueError: not an attribute.
    """
    assert attribute_docs(doc) == {
        "alpha": "first line goes on here.",
        "beta": "typed entry.",
        "gamma": "``x`` and :mod:`a.b`.",
    }
    assert attribute_docs("No sections.") == {}
    assert attribute_docs(None) == {}


def test_plain_text_drops_markup():
    assert (
        plain_text("``fast`` or :mod:`~seenerf.data.subframes`") == "fast or seenerf.data.subframes"
    )


def test_every_fit_config_field_has_help():
    docs = attribute_docs(FitConfig.__doc__)
    assert [f.name for f in dataclasses.fields(FitConfig)] == list(docs)
    assert all(docs.values())


@dataclass
class _Example:
    """Example.

    Attributes:
        count: how many.
        wait_s: how long.
        marks_s: when.
        loud: say more.
        check: check things.
    """

    count: int = 3
    wait_s: float = 0.0
    marks_s: tuple[float, ...] = ()
    loud: bool = False
    check: bool = True


def test_options_follow_the_fields():
    parser = argparse.ArgumentParser()
    add_dataclass_options(parser, _Example, seconds=lambda text: float(text) * 60)
    assert _Example(**dataclass_values(_Example, parser.parse_args([]))) == _Example()
    args = parser.parse_args(
        ["--count", "5", "--wait", "2", "--marks", "0.5", "1", "--loud", "--no-check"]
    )
    assert _Example(**dataclass_values(_Example, args)) == _Example(
        5, 120.0, (0.5, 1.0), True, False
    )
    text = parser.format_help()
    assert "how many (default: 3)" in text and "turn off: check things" in text


def _fit_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    fit_verb.add_arguments(parser)
    return parser


def test_fit_verb_defaults_are_fit_config_defaults(tmp_path):
    args = _fit_parser().parse_args([str(tmp_path)])
    assert fit_verb.config_from_options(args) == FitConfig()
    assert (args.session, args.run, args.fresh, args.ray) == ([tmp_path], None, False, None)


def test_fit_verb_keeps_its_option_names(tmp_path):
    args = _fit_parser().parse_args(
        [str(tmp_path), "--preset", "paper", "--variant", "base", "--time-budget", "10m"]
        + ["--steps", "7", "--device", "cpu", "--threshold", "0.35", "--subframes", "2"]
        + ["--bins", "6", "--low-pass", "paper", "--seed", "3", "--threads", "2"]
        + ["--no-registration", "--fresh", "--run", "mine", "--exposures", "0.01", "0.02"]
        + ["--no-dead-time"]
    )
    config = fit_verb.config_from_options(args)
    assert config == FitConfig.of(
        preset="paper",
        variant="base",
        time_budget_s=600.0,
        steps=7,
        device="cpu",
        threshold=0.35,
        subframes=2,
        bins=6,
        low_pass="paper",
        seed=3,
        threads=2,
        register_test_views=False,
        exposures_s=(0.01, 0.02),
        dead_time=False,
    )
    assert (args.fresh, args.run) == (True, "mine")
