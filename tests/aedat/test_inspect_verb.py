"""``seecap inspect``: text and JSON on the fixture, and delegation of folders and raw dumps."""

import json
import sys
import types

from davis_io.cli import main


def test_text_output_lists_fixture_facts(aestream_aedat4, capsys):
    assert main(["inspect", str(aestream_aedat4)]) == 0
    text = capsys.readouterr().out
    assert "DAVIS346 (serial 00000104)" in text and "346 x 260" in text
    assert "117,667 in 13 packets, 72,363 ON" in text
    assert "1633953690976518, 1633953691016518, 1633953691056518" in text
    assert "exposure    4,773 µs, interval 40,000 µs" in text


def test_json_output(aestream_aedat4, capsys):
    assert main(["inspect", "--json", str(aestream_aedat4)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["events"]["count"] == 117_667 and data["frame_exposures_us"] == [4773] * 3
    assert data["time_range_us"] == [1633953690967091, 1633953691110744]


def test_bad_file_is_an_error_exit(tmp_path, capsys):
    path = tmp_path / "x.aedat4"
    path.write_bytes(b"")
    assert main(["inspect", str(path)]) == 1
    assert "empty file" in capsys.readouterr().err


def test_folder_is_described_as_a_session(tmp_path, monkeypatch):
    calls = []
    fake = types.ModuleType("davis_io.session.inspect")
    fake.describe_session = lambda path, args: calls.append(path) or 0
    monkeypatch.setitem(sys.modules, "davis_io.session.inspect", fake)
    assert main(["inspect", str(tmp_path)]) == 0 and calls == [tmp_path]


def test_raw_usb_dump_goes_through_the_same_summary(aestream_aedat4, monkeypatch, capsys):
    from davis_io.aedat import open_recording

    opened = []
    fake = types.ModuleType("davis_io.usb.dump")
    fake.open_raw_usb_dump = lambda path, model: opened.append(model) or open_recording(path)
    monkeypatch.setitem(sys.modules, "davis_io.usb.dump", fake)
    assert main(["inspect", "--raw-usb", "DAVIS346", str(aestream_aedat4)]) == 0
    assert opened == ["DAVIS346"] and "117,667" in capsys.readouterr().out
