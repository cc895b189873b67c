"""A user's mistake gets one line ``seecap: error: ...`` and an exit status, never a traceback."""

import io
import os
import sys

import pytest

from davis_io.cli import main
from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record

TINY = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=1, exposure_us=40_000)


@pytest.fixture(scope="module")
def tiny_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli") / "tiny"
    record(EmulatedCamera("room", seed=1, **TINY), folder)
    return folder


def run(capsys, *argv):
    try:
        status = main(list(argv))
    except SystemExit as stop:  # argparse's own usage errors
        status = stop.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return status, err.strip().splitlines()[-1]


@pytest.mark.parametrize(
    "argv, status, line",
    [
        (["inspect", "nonexistent.aedat4"], 1, "nonexistent.aedat4: No such file or directory"),
        (["record", "--replay", "gone.aedat4", "--out", "{tmp}/s"], 1, "gone.aedat4: No such"),
        (["record", "--emulate", "room", "--exposure", "-1"], 2, "must be > 0"),
        (["record", "--emulate", "room", "--exposure", "soon"], 2, "'soon' is not a duration"),
        (["record", "--sensor", "random"], 2, "use them with --emulate"),
        (["record", "--auto-exposure", "1,0.5"], 2, "use them with --emulate"),
        (["record", "--emulate", "room", "--auto-exposure", "1,2"], 2, "shares of the exposure"),
        (["record", "--emulate", "room", "--auto-exposure", "half"], 2, "e.g. 1,0.5,0.25"),
        (["record", "--camera", "DAVIS240"], 2, "use them with --emulate"),
        (["record", "--emulate", "room", "--camera", "DAVIS128"], 2, "invalid choice"),
        (["fit", "{tmp}", "--time-budget", "abc"], 2, "'abc' is not a duration"),
        (["render", "{tmp}", "--path", "orbit", "--exposure", "-1"], 2, "must be > 0"),
        (["render", "{tmp}", "--path", "orbit", "--exposure", "0"], 2, "must be > 0"),
    ],
)
def test_a_bad_argument_is_one_line(capsys, tmp_path, argv, status, line):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    code, last = run(capsys, *argv)
    assert code == status and line in last and "error:" in last


def test_export_into_a_missing_folder_is_one_line(capsys, tiny_session):
    code, last = run(capsys, "export", str(tiny_session), "--aedat4", "/missing-dir/x.aedat4")
    assert code == 1 and last == (
        "seecap: error: export: /missing-dir/x.aedat4: No such file or directory"
    )


class _ClosedPipe(io.TextIOBase):
    """Standard output whose reader has gone, as after ``seecap inspect ... | head -1``."""

    def __init__(self, fd):
        self.fd = fd

    def write(self, text):
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self):
        return self.fd


def test_a_closed_pipe_ends_quietly(monkeypatch, capsys, tiny_session, tmp_path):
    fd = os.open(tmp_path / "out", os.O_WRONLY | os.O_CREAT)
    monkeypatch.setattr(sys, "stdout", _ClosedPipe(fd))
    assert main(["inspect", str(tiny_session), "--json"]) == 0
    assert capsys.readouterr().err == ""
    os.close(fd)


def test_debug_shows_the_traceback(capsys):
    with pytest.raises(FileNotFoundError):
        main(["--debug", "inspect", "nonexistent.aedat4"])
