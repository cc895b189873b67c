"""Every verb's parser and every value check, driven by hypothesis with hostile values.

Each example is one ``seecap VERB ...`` command line: the verb's own options, each given a value
from a pool of NaN, infinities, negatives, zero, huge numbers, wrong types and path tricks. The
command must end in one of its documented exit statuses with one error line: never a
traceback, never a "this is a bug" line, a usage error always 2. The positional argument names a
folder that holds no session (or a file), so nothing valid ever starts a long job.

``SEECAP_FUZZ_EXAMPLES`` sets the examples per verb (``make fuzz``: 500; the suite: 100).
"""

import argparse
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from davis_io.cli import VERBS, _build_parser, main

EXAMPLES = int(os.environ.get("SEECAP_FUZZ_EXAMPLES", "100"))

VALUES = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "-1e400",
    "-1",
    "-0",
    "0",
    "0.0",
    "1e-400",
    "1e20",
    "99999999999999999999",
    "1",
    "2",
    "0.15",
    "150ms",
    "10m",
    "1h",
    "-5s",
    "abc",
    "",
    " ",
    "0x10",
    "1,5",
    "١",
    "../..",
    "/",
    "/abs/path",
    "a/b",
    ".",
    "..",
    "fast",
    "full",
    "cpu",
    "orbit",
    "RGGB",
    "mono",
    "room",
    "davis346",
    "\x00",
]
"""Values every option may get: numbers a check must refuse, words, and path tricks."""

UNSAFE = {
    "--ray",  # would start or join a Ray cluster
    "--install",  # would write the machine's udev rules
    "--replay",  # a real file would be recorded
    "--preview",
}
"""Options that would reach outside the test (their checks have tests of their own)."""


def _options(verb: str) -> list[tuple[str, bool]]:
    """``(option string, takes a value)`` of every option of ``verb``."""
    parser, _ = _build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    options = []
    for action in sub.choices[verb]._actions:
        for string in action.option_strings:
            if string.startswith("--") and string not in UNSAFE and string != "--help":
                options.append((string, action.nargs != 0))
    return options


def _command(verb: str, options, folder: str):
    chosen = st.lists(st.sampled_from(options), max_size=4) if options else st.just([])
    return st.tuples(chosen, st.lists(st.sampled_from(VALUES), min_size=4, max_size=4)).map(
        lambda drawn: _argv(verb, drawn, folder)
    )


def _argv(verb: str, drawn, folder: str) -> list[str]:
    chosen, values = drawn
    argv = [verb]
    if verb in ("inspect", "bins", "calibrate", "poses", "export", "fit", "render", "eval"):
        argv.append(folder)
    for (option, takes_value), value in zip(chosen, values, strict=False):
        argv += [option, value] if takes_value else [option]
    if verb == "record":
        argv += ["--emulate", "room", "--out", folder]  # a folder without a session: refused
    return argv


@pytest.fixture(scope="module")
def not_a_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz") / "photos"
    folder.mkdir()
    (folder / "keep.jpg").write_bytes(b"not a session")
    return str(folder)


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_hostile_command_lines_end_in_one_line_and_a_documented_status(verb, not_a_session, capsys):
    options = _options(verb)

    @settings(
        # doctor runs its checks (about a second) on every example; its one option is --path
        max_examples=min(EXAMPLES, 3) if verb == "doctor" else EXAMPLES,
        deadline=None,
        derandomize=True,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )
    @given(_command(verb, options, not_a_session))
    def check(argv):
        try:
            status = main(argv)
        except SystemExit as stop:  # argparse's own usage errors
            status = stop.code
        err = capsys.readouterr().err
        assert "Traceback" not in err, (argv, err)
        assert "this is a bug" not in err, (argv, err)
        assert status in (0, 1, 2), (argv, status, err)
        if status == 2:
            assert "error" in err, (argv, err)
        assert os.listdir(not_a_session) == ["keep.jpg"], argv  # nothing written or deleted

    check()
