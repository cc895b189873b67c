import math

import numpy as np
from benchlib.capture import CAPTURE_BENCHES, figures_from, read_result
from benchlib.tool_result import result_line

DECODE, USB, RECORD = CAPTURE_BENCHES


def test_figures_of_the_decode_result_in_millions():
    result = {
        "events": 5012345,
        "file_mb": 31.2,
        "repeats": 3,
        "ours_ev_s": 88.5e6,
        "python_lz4_ev_s": 55.0e6,
        "dv_ev_s": 61.0e6,
        "ratio": 1.45,
        "python_lz4_ratio": 0.9,
        "liblz4": True,
        "command": "x",
        "machine": "y",
    }
    figures = figures_from(DECODE, result)
    assert figures.keys() == {
        "events",
        "ours_mev_s",
        "python_lz4_mev_s",
        "dv_mev_s",
        "ratio",
        "python_lz4_ratio",
    }
    assert figures["events"] == 5012345.0 and figures["ratio"] == 1.45
    assert math.isclose(figures["python_lz4_mev_s"], 55.0) and figures["python_lz4_ratio"] == 0.9
    assert math.isclose(figures["ours_mev_s"], 88.5) and math.isclose(figures["dv_mev_s"], 61.0)


def test_figures_of_the_usb_result_read_nested_keys():
    result = {
        "decoder": {"words": 3.1e6, "seconds": 0.05, "mwords_s": 62.0, "mevents_s": 48.8},
        "end_to_end": {"mevents_s": 11.98, "lag_max_s": 0.035, "packets_lost": 0},
    }
    figures = figures_from(USB, result)
    assert figures == {
        "decoder_mwords_s": 62.0,
        "decoder_mev_s": 48.8,
        "e2e_mev_s": 11.98,
        "e2e_lag_ms": 35.0,
        "e2e_overflow": 0.0,
    }


def test_figures_of_a_partial_record_result_leave_the_missing_out():
    result = {
        "binning_s": {"b4": 0.21},
        "capacity": {"events_per_s": 18.4e6},
        "recording": {"dropped_events": 0, "events_per_s": "not a number"},
    }
    figures = figures_from(RECORD, result)
    assert figures.keys() == {"binning_b4_s", "capacity_mev_s", "drops"}
    assert figures["binning_b4_s"] == 0.21 and math.isclose(figures["capacity_mev_s"], 18.4)
    assert figures_from(RECORD, {}) == {}


def test_the_result_line_round_trips_numpy_values_and_is_found_after_other_output():
    line = result_line(
        {
            "events": np.int64(7),
            "ratio": np.float32(0.5),
            "lag": float("nan"),
            "nested": {"b4": np.float64(0.25)},
        }
    )
    text = f"warning: something\n{line}\nexit\n"
    result = read_result(text)
    assert result["events"] == 7 and result["ratio"] == 0.5 and result["nested"] == {"b4": 0.25}
    assert math.isnan(result["lag"])
    assert read_result("decoder: 62.0 M words/s\n") is None
