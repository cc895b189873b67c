"""Several sessions in one ``seecap fit``: in turn without Ray (never imported), failures apart."""

import signal
import subprocess
import sys
from pathlib import Path

import seenerf.cli.sessions
from davis_io.cli import main
from davis_io.errors import SessionError
from seenerf.cli.sessions import SessionFit, score_table
from seenerf.errors import TrainingStopped
from seenerf.train.fit import FitResult

TINY_FIT = Path(__file__).parents[1] / "seenerf" / "tiny_fit.py"


def _metrics(hdr, novel, contrast, steps):
    return {
        "hdr": {"psnr": hdr},
        "novel_exposure": {"psnr": novel},
        "log_contrast": contrast,
        "training": {"steps": steps},
    }


def test_score_table_rows_and_columns():
    fits = [
        SessionFit(Path("a"), Path("a/fit/fast-full"), _metrics(31.234, 28.0, [0.9, 1.0], 900)),
        SessionFit(Path("long/name"), error="no session.json"),
        SessionFit(Path("c"), Path("c/fit/fast-full"), {"training": {"steps": 12}}),
    ]
    assert score_table(fits).splitlines() == [
        "session    run        HDR dB  novel dB  log contrast  steps  result",
        "a          fast-full   31.23     28.00         0.950    900  fitted",
        "long/name  -               -         -             -      -  failed",
        "c          fast-full       -         -             -     12  fitted",
    ]


def test_sessions_in_turn_a_failure_is_reported_and_the_others_fit(monkeypatch, tmp_path, capsys):
    order = []

    def fake(session, config, **options):
        order.append(session.name)
        if session.name == "broken":
            raise SessionError(f"{session}/session.json is damaged: record it again")
        return FitResult(session / "fit" / "r", None, _metrics(30.0, 29.0, [1.0], 5))

    monkeypatch.setattr(seenerf.cli.sessions, "prepare_and_fit", fake)
    folders = [tmp_path / name for name in ("one", "broken", "two")]
    assert main(["fit", *map(str, folders), "--quiet"]) == 1
    assert order == ["one", "broken", "two"]
    out, err = capsys.readouterr()
    rows = out.splitlines()[1:]
    assert [row.split()[-1] for row in rows] == ["fitted", "failed", "fitted"]
    assert err.splitlines() == [
        f"seecap: error: fit: {folders[1]}: {folders[1]}/session.json is damaged: record it again"
    ]


def test_a_stop_ends_every_session_not_just_one(monkeypatch, tmp_path, capsys):
    order = []

    def fake(session, config, **options):
        order.append(session.name)
        raise TrainingStopped("stopped at step 7 (SIGTERM); checkpoint saved in x", signal.SIGTERM)

    monkeypatch.setattr(seenerf.cli.sessions, "prepare_and_fit", fake)
    assert main(["fit", str(tmp_path / "one"), str(tmp_path / "two"), "--quiet"]) == 143
    assert order == ["one"]


def test_without_ray_installed_the_error_names_the_install_command(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails
    assert main(["fit", str(tmp_path), "--ray", "local", "--quiet"]) == 1
    assert capsys.readouterr().err.strip() == (
        "seecap: error: fit: Ray is not installed: pip install -e '.[cluster]' installs it "
        "(or pip install ray)"
    )


def test_a_plain_fit_never_imports_ray(tmp_path):
    done = subprocess.run(
        [sys.executable, str(TINY_FIT), str(tmp_path / "session")],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "ray imported: False"
