"""Damaged and truncated recordings: one line naming what is wrong, exit 1, nothing lost."""

import json

import h5py
import pytest

from davis_io.aedat import Aedat4Reader
from davis_io.cli import main
from davis_io.errors import SessionError
from davis_io.session import Session
from davis_io.session.manifest import SessionManifest

pytest.importorskip("dv_processing")


@pytest.fixture
def session_folder(tmp_path, aestream_aedat4, capsys):
    folder = tmp_path / "s"
    assert main(["record", "--replay", str(aestream_aedat4), "--out", str(folder)]) == 0
    capsys.readouterr()
    return folder


def _one_line_failure(capsys, argv) -> str:
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    return err


def test_a_truncated_replay_is_flagged_with_what_was_lost(tmp_path, aestream_aedat4, capsys):
    with Aedat4Reader(aestream_aedat4) as reader:
        cut = reader.data_table[31].byte_offset - 8 + 100  # inside packet 31, of events
        last_kept_us = max(e.timestamp_end for e in reader.data_table[:31])
        full_count = sum(len(p.events) for p in reader)
    path = tmp_path / "cut.aedat4"
    path.write_bytes(aestream_aedat4.read_bytes()[:cut])
    folder = tmp_path / "s"
    code = main(["record", "--replay", str(path), "--out", str(folder)])
    captured = capsys.readouterr()
    assert code == 1
    reason = f"truncated at byte offset {cut - 100}"
    assert reason in captured.err.splitlines()[-1]
    with Session.open(folder) as session:
        manifest = session.manifest
        assert manifest.status == "interrupted" and reason in manifest.stop_reason
        assert any(reason in note for note in manifest.source_notes)
        assert 0 < session.event_count < full_count
        assert session.events_between(0, 2**62)["t"].max() <= last_kept_us
    report = main(["inspect", str(folder)])
    lines = capsys.readouterr().out.splitlines()
    assert report == 0 and lines[0].startswith("status") and reason in lines[0]


def test_a_file_cut_before_any_data_is_not_a_complete_session(tmp_path, aestream_aedat4, capsys):
    path = tmp_path / "cut.aedat4"
    path.write_bytes(aestream_aedat4.read_bytes()[:21_000])
    assert main(["record", "--replay", str(path), "--out", str(tmp_path / "s")]) == 1
    assert "truncated" in capsys.readouterr().err
    assert json.loads((tmp_path / "s" / "session.json").read_text())["status"] == "interrupted"


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"width": "abc"}, "field 'width' must be int, not 'abc'"),
        ({"height": 0}, "field 'height' 0 is out of range"),
        ({"frame_count": True}, "field 'frame_count' must be int, not True"),
        ({"exposure_measured_us": "x"}, "field 'exposure_measured_us' must be int or null"),
        ({"colour": "mono"}, "unknown field 'colour'"),
        ({"drops": {"queue_events": -0.5}}, "drops: field 'queue_events' must be int"),
    ],
)
def test_a_manifest_field_of_the_wrong_type_is_named(session_folder, capsys, change, named):
    path = session_folder / "session.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), **change}))
    err = _one_line_failure(capsys, ["inspect", str(session_folder)])
    assert named in err and "session.json" in err


def test_a_missing_field_is_named():
    with pytest.raises(SessionError, match="missing field 'width'"):
        SessionManifest.from_json(json.dumps({"format_version": 1, "camera": "DAVIS346"}))


def test_a_manifest_that_is_not_utf8_names_the_byte(session_folder, capsys):
    path = session_folder / "session.json"
    text = path.read_bytes()
    at = text.index(b"DAVIS346")
    path.write_bytes(text[:at] + b"\xff" + text[at + 1 :])
    err = _one_line_failure(capsys, ["inspect", str(session_folder)])
    assert f"byte offset {at} is not UTF-8" in err


def test_a_deleted_dataset_is_named_by_every_verb(session_folder, capsys):
    with h5py.File(session_folder / "session.h5", "r+") as h5:
        del h5["frames"]
    for argv in (["inspect"], ["bins", "--bins", "6"], ["calibrate"], ["poses"]):
        err = _one_line_failure(capsys, [*argv, str(session_folder)])
        assert "/frames/" in err and "is missing" in err


def test_counts_that_disagree_with_the_manifest_are_named(session_folder, capsys):
    path = session_folder / "session.json"
    values = json.loads(path.read_text())
    path.write_text(json.dumps({**values, "event_count": values["event_count"] + 1}))
    err = _one_line_failure(capsys, ["inspect", str(session_folder)])
    assert f"holds {values['event_count']}" in err and "'event_count'" in err


def test_an_event_outside_the_sensor_is_named_with_its_index(session_folder, capsys):
    with h5py.File(session_folder / "session.h5", "r+") as h5:
        x = h5["events/x"]
        x[1234] = 29044
        t = int(h5["events/t"][1234])
    err = _one_line_failure(capsys, ["inspect", str(session_folder)])
    assert f"event 1234, t={t} µs lies at x=29044" in err and "346x260 sensor" in err
    with Session.open(session_folder) as session, pytest.raises(SessionError, match="x=29044"):
        session.events_between(t, t)
