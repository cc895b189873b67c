import math

from benchlib.capture import CAPTURE_BENCHES, CaptureResult
from benchlib.numbers import fmt
from benchlib.paper import TABLE_9_CRF
from benchlib.results import ProcessUsage, RunRow
from benchlib.tables import capture_table, comparison_lines, markdown_table, runs_table
from benchlib.verdicts import judge


def test_markdown_table_layout_and_escaping():
    text = markdown_table(["a", "b"], [["1", "x|y"], ["", "2"]])
    assert text == "| a | b |\n| --- | --- |\n| 1 | x\\|y |\n|  | 2 |"


def test_empty_table_has_header_only():
    assert markdown_table(["a"], []) == "| a |\n| --- |"


def test_fmt_rounds_and_dashes_missing_values():
    assert fmt(24.125, 1) == "24.1"
    assert fmt(3.14159) == "3.14"
    assert fmt(math.nan) == "—"
    assert fmt(None) == "—"
    assert fmt(math.inf) == "—"


def test_runs_are_sorted_by_session_preset_variant_budget():
    usage = ProcessUsage(0, 70.0, 130.0, 1234.4)
    rows = [
        RunRow(
            "room",
            "fast",
            "full",
            180.0,
            hdr_psnr=21.0,
            registered_hdr_psnr=23.456,
            registered_novel_psnr=22.0,
            process=usage,
        ),
        RunRow("room", "balanced", "full", 60.0, hdr_psnr=19.0),
        RunRow("room", "fast", "full", 60.0, hdr_psnr=20.0),
    ]
    lines = runs_table(rows).splitlines()[2:]
    assert [line.split(" | ")[1:4] for line in lines] == [
        ["balanced", "full", "1 min"],
        ["fast", "full", "1 min"],
        ["fast", "full", "3 min"],
    ]
    # Process wall, CPU and peak MB of the 3 min row, rounded to whole numbers.
    assert "| 70 | 130 | 1234 | ok |" in lines[2]
    # The registered scores beside the mapped ones; a run without them shows dashes.
    assert "| 23.46 / 22.00 |" in lines[2] and "| — / — |" in lines[0]


def test_comparison_lines_show_paper_beside_ours_and_the_verdict():
    rows = {
        "full": RunRow("room", "fast", "full", 30.0, hdr_psnr=22.5, hdr_ssim=0.81234, steps=12),
        "power-crf": None,
    }
    lines = comparison_lines(judge(TABLE_9_CRF, rows), rows)
    table = "\n".join(lines)
    assert "| full | See-NeRF | 26.49 / 0.8953 | 32.70 / 0.9564 | 22.50 / 0.8123 |" in table
    assert (
        "| power-crf | See-NeRF^Pow | 19.75 / 0.7239 | 28.35 / 0.9242 | — | — | — | not run |"
        in table
    )
    assert "**Paper's ordering here: not measured.**" in lines
    assert lines[-1] == "- not measured (a run missing or failed): full > power-crf"


def test_capture_table_lists_each_figure_with_its_target():
    bench = CAPTURE_BENCHES[2]
    result = CaptureResult(
        bench, [], ProcessUsage(0, 9.0, 8.0, 512.0), figures={"binning_b4_s": 0.1234, "drops": 3.0}
    )
    table = capture_table([result])
    assert "| bench_record.py | binning 1 M events, b=4, s | 0.123 | < 0.5 | met | 512 |" in table
    assert "| bench_record.py | recording, dropped events | 3 | == 0 | **missed** | 512 |" in table
    assert "| bench_record.py | binning 1 M events, b=6, s | — | < 0.5 |  | 512 |" in table


def test_comparison_lines_print_each_measured_ordering_with_its_gap():
    rows = {
        "full": RunRow("room", "fast", "full", 30.0, hdr_psnr=22.5),
        "power-crf": RunRow("room", "fast", "power-crf", 30.0, hdr_psnr=23.0),
    }
    lines = comparison_lines(judge(TABLE_9_CRF, rows), rows)
    reversed_line = [line for line in lines if line.startswith("- paper:")]
    assert len(reversed_line) == 1
    assert reversed_line[0].startswith(
        "- paper: full > power-crf (26.49 vs 19.75 dB, real HDR); here: **reversed** "
        "(22.50 vs 23.00 dB, -0.50). Measured: training 0 vs 0 steps"
    )
