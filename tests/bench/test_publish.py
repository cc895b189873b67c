import json

import pytest
from benchlib.machine import Machine
from benchlib.plan import make_plan
from benchlib.publish import BEGIN, END, RESULTS_FOLDER, publish, splice
from benchlib.report import BenchReport, render_markdown, write_json
from benchlib.results import RunRow
from benchlib.sessions import SessionOutcome

MACHINE = Machine("Test CPU", 2, "Linux", "3.11", "2.0", "2.13", "cpu", 2, (1.0, 0.5, 0.25))


def full_run_report(sessions=()):
    plan = make_plan(False, ("fast",), ("full",))
    rows = [RunRow("room", "fast", "full", 600.0, hdr_psnr=31.0, novel_psnr=30.5, steps=6000)]
    report = BenchReport("python tools/bench.py", MACHINE, "2026-01-01 00:00 UTC", plan, "truth")
    report.rows, report.sessions = rows, list(sessions)
    return report


def test_splice_replaces_only_the_text_between_the_markers():
    document = f"# Title\n\nkept above\n{BEGIN}\nold report\n{END}\nkept below\n"
    spliced = splice(document, "## New\n\nnumbers\n")
    assert spliced == f"# Title\n\nkept above\n{BEGIN}\n\n## New\n\nnumbers\n\n{END}\nkept below\n"
    assert splice(spliced, "## New\n\nnumbers") == spliced  # idempotent


@pytest.mark.parametrize(
    "document",
    ["no markers", f"{BEGIN}\nonly the start", f"{END}\n{BEGIN}\n", f"{BEGIN}{BEGIN}{END}"],
)
def test_splice_refuses_a_document_without_one_ordered_pair_of_markers(document):
    with pytest.raises(ValueError, match="BENCHMARKS.md"):
        splice(document, "report")


def test_publish_links_the_copied_plot_and_keeps_the_hand_written_text(tmp_path):
    out = tmp_path / "bench-out"
    (out / "scenes").mkdir(parents=True)
    spec = make_plan(False, ("fast",), ("full",)).sessions[0]
    report = full_run_report([SessionOutcome(spec, out / "sessions" / "room")])
    (out / report.plot_name).write_bytes(b"png bytes")
    (out / "scenes" / "room.png").write_bytes(b"room views")
    write_json(report, out / "results.json")
    document = tmp_path / "BENCHMARKS.md"
    document.write_text(f"# Benchmarks\n\n{BEGIN}\n{END}\n\n## Analysis\n")

    folder = publish(report, out, document)

    assert folder == tmp_path / RESULTS_FOLDER
    assert (folder / report.plot_name).read_bytes() == b"png bytes"
    assert (folder / "scenes" / "room.png").read_bytes() == b"room views"
    assert json.loads((folder / "results.json").read_text())["rows"][0]["hdr_psnr"] == 31.0
    text = document.read_text()
    assert f"![speed against error]({RESULTS_FOLDER}/{report.plot_name})" in text
    assert f"![room: truth, full, oracle, error]({RESULTS_FOLDER}/scenes/room.png)" in text
    assert text.startswith("# Benchmarks\n") and text.endswith(f"{END}\n\n## Analysis\n")
    assert "| room | fast | full |" in text


def test_json_paths_under_the_working_folder_are_relative(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = make_plan(False, ("fast",), ("full",)).sessions[0]
    report = full_run_report([SessionOutcome(spec, tmp_path / "sessions" / "room")])
    write_json(report, tmp_path / "results.json")
    text = (tmp_path / "results.json").read_text()
    assert str(tmp_path) not in text
    assert json.loads(text)["sessions"][0]["folder"] == "sessions/room"


def test_render_only_writes_the_report_again_from_results_json(tmp_path, capsys):
    import bench

    report = full_run_report()
    write_json(report, tmp_path / "results.json")
    assert bench.main(["--out", str(tmp_path), "--render-only"]) == 0
    assert (tmp_path / "report.md").read_text() == render_markdown(report)
    assert (tmp_path / report.plot_name).stat().st_size > 0
    payload = json.loads((tmp_path / "results.json").read_text())
    payload["rows"][0]["mapped_hdr_psnr"] = 24.0  # a field this version does not write
    (tmp_path / "results.json").write_text(json.dumps(payload))
    assert bench.main(["--out", str(tmp_path), "--render-only"]) == 1
    assert "RunRow has no field mapped_hdr_psnr" in capsys.readouterr().err


def test_a_kept_report_is_published_between_its_tools_markers(tmp_path, monkeypatch, capsys):
    from benchlib import publish as publish_module

    begin, end = publish_module.section_markers("bench_sharing.py")
    assert (begin, end) == (publish_module.SHARING_BEGIN, publish_module.SHARING_END)
    (tmp_path / "BENCHMARKS.md").write_text(f"# head\n{begin}\nold\n{end}\ntail\n")
    monkeypatch.setattr(publish_module, "REPOSITORY", tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    publish_module.keep_report(out, "sharing", {"a": 1}, "| new |", publish=False)
    assert (out / "sharing.md").read_text() == "| new |\n" and "| new |" in capsys.readouterr().out
    assert "old" in (tmp_path / "BENCHMARKS.md").read_text()  # not published
    publish_module.keep_report(out, "sharing", {"a": 1}, "| new |", publish=True)
    assert (
        tmp_path / "BENCHMARKS.md"
    ).read_text() == f"# head\n{begin}\n\n| new |\n\n{end}\ntail\n"
    assert json.loads((tmp_path / "bench-results" / "sharing.json").read_text()) == {"a": 1}
