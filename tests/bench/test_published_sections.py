"""BENCHMARKS.md's generated sections are exactly what their files in bench-results/ render to."""

import json
from pathlib import Path

import pytest
from benchlib.blind import blind_report
from benchlib.lens import lens_report
from benchlib.publish import (
    BEGIN,
    BLIND_BEGIN,
    BLIND_END,
    CLUSTER_BEGIN,
    CLUSTER_END,
    END,
    LENS_BEGIN,
    LENS_END,
    SHARING_BEGIN,
    SHARING_END,
    as_published,
)
from benchlib.readback import report_from_json
from benchlib.report import render_markdown
from benchlib.sharing import sharing_report
from benchlib.side_by_side import side_by_side_report

ROOT = Path(__file__).resolve().parents[2]


def _section(begin: str, end: str) -> str:
    text = (ROOT / "BENCHMARKS.md").read_text()
    return text.split(begin)[1].split(end)[0].strip()


@pytest.mark.parametrize(
    ("name", "render", "begin", "end"),
    [
        ("blind.json", blind_report, BLIND_BEGIN, BLIND_END),
        ("cluster.json", side_by_side_report, CLUSTER_BEGIN, CLUSTER_END),
        ("lens.json", lens_report, LENS_BEGIN, LENS_END),
        ("sharing.json", sharing_report, SHARING_BEGIN, SHARING_END),
    ],
    ids=["blind", "cluster", "lens", "sharing"],
)
def test_a_generated_section_holds_what_its_results_file_renders_to(name, render, begin, end):
    document = json.loads((ROOT / "bench-results" / name).read_text())
    assert _section(begin, end) == render(document).strip()


def test_the_main_section_holds_what_results_json_renders_to():
    report = report_from_json(ROOT / "bench-results" / "results.json")
    assert _section(BEGIN, END) == render_markdown(as_published(report)).strip()
