from benchlib.capture import CAPTURE_BENCHES, parse_output

DECODE, USB, RECORD = CAPTURE_BENCHES


def test_parse_decode_output():
    text = ("file: 5,012,345 events, 31.2 MB, LZ4\n"
            "ours:             88.5 M events/s (best of 3)\n"
            "dv-processing:    61.0 M events/s (best of 3)\n"
            "ratio ours / dv-processing: 1.45\n")
    assert parse_output(DECODE, text) == {"events": 5012345.0, "ours_mev_s": 88.5,
                                          "dv_mev_s": 61.0, "ratio": 1.45}


def test_parse_usb_output():
    text = ("decoder: 3.1 M words (1.27 words/event) in 0.050 s: 62.0 M words/s, 48.8 M events/s "
            "(target >= 50 M words/s)\n"
            "end to end: 2.10 s of stream at 12 M events/s in 2.20 s wall; received 100 of 100 "
            "events (11.98 M events/s of stream time); max lag 35 ms; host queue overflow 0 "
            "packets (0 events)\n")
    assert parse_output(USB, text) == {"decoder_mwords_s": 62.0, "decoder_mev_s": 48.8,
                                       "e2e_mev_s": 11.98, "e2e_lag_ms": 35.0,
                                       "e2e_overflow": 0.0}


def test_parse_record_output_and_missing_figures():
    text = ("binning + h() of 1 M events, 346x260, b=4: 0.210 s (target < 0.5 s) ok\n"
            "capacity (unpaced, waiting queue): 18.40 M events/s wall; 0.61 CPU-seconds\n"
            "drops: 0 events in 0 packets (target 0) ok\n")
    assert parse_output(RECORD, text) == {"binning_b4_s": 0.21, "capacity_mev_s": 18.4,
                                          "drops": 0.0}
    assert parse_output(RECORD, "") == {}
