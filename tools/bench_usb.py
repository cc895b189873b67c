"""Benchmark: DAVIS USB word decoding, and the driver end to end through the emulated DAVIS346.

1. Decoder: an event-heavy stream (12 M events/s of random DAVIS346 events, encoded as the
   device sends them: timestamp word per new µs, row word per new row, column word per event)
   decoded in 128 KiB transfers on one core; best of N runs.
2. End to end: the same kind of stream at 12 M events/s, replayed by the emulated device in
   real time (no faster than its own clock), read by ``DavisCamera`` (pyusb, reader thread,
   bounded queue) and consumed by a loop counting events; reports throughput, lag and the
   host queue overflow, which must be zero.

    python tools/bench_usb.py [--quick] [--seconds S] [--rate EVENTS_PER_S]

Other tools call :func:`run`, which returns the printed numbers as a dict.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np
from benchlib.targets import QUEUE_OVERFLOW, USB_DECODER_MWORDS_S

from davis_io.types import EVENT_DTYPE, Packet
from davis_io.usb.device import open_camera
from davis_io.usb.emulated import EmulatedBackend, EmulatedDavis346, looped_words
from davis_io.usb.encode import StreamEncoder, time_words
from davis_io.usb.layout import SensorLayout
from davis_io.usb.words import WordDecoder

LAYOUT = SensorLayout()
WRAP_US = 1 << 15
TRANSFER_BYTES = 131072


def event_block(rate: float, wraps: int, seed: int = 0) -> tuple[np.ndarray, int]:
    """Words of ``wraps`` x 32768 µs of random events at ``rate`` per second; and their count."""
    span = wraps * WRAP_US
    n = int(rate * span / 1e6)
    rng = np.random.default_rng(seed)
    events = np.zeros(n, EVENT_DTYPE)
    events["t"] = np.sort(rng.integers(0, span, n))
    events["x"], events["y"] = rng.integers(0, 346, n), rng.integers(0, 260, n)
    events["p"] = rng.choice(np.array([-1, 1], np.int8), n)
    encoder = StreamEncoder(LAYOUT, time_origin_us=0, hold_us=0)
    words = encoder.encode_all([Packet(events=events)])
    closing = np.array(time_words(encoder.device_time_us, span), dtype=np.uint16)
    return np.concatenate([words, closing]), n


def bench_decoder(words: np.ndarray, n_events: int, repeats: int) -> dict:
    data = words.astype("<u2").tobytes()
    best = float("inf")
    for _ in range(repeats):
        decoder = WordDecoder(LAYOUT)
        start = time.perf_counter()
        for offset in range(0, len(data), TRANSFER_BYTES):
            decoder.decode(data[offset : offset + TRANSFER_BYTES])
        best = min(best, time.perf_counter() - start)
        if decoder.stats.events != n_events:
            raise SystemExit(f"decoder lost events: {decoder.stats.events} of {n_events}")
    return {
        "words": len(words),
        "seconds": best,
        "mwords_s": len(words) / best / 1e6,
        "mevents_s": n_events / best / 1e6,
    }


def bench_end_to_end(block: np.ndarray, block_events: int, seconds: float) -> dict:
    block_us = WRAP_US * 4
    repeats = max(1, round(seconds * 1e6 / block_us))
    device = EmulatedDavis346(chunks=looped_words(block, block_us, repeats), realtime=True)
    received, lag_max = 0, 0.0
    with open_camera(backend=EmulatedBackend(device)) as camera:
        start = time.monotonic()
        for packet in camera:
            received += len(packet.events)
            if len(packet.events):
                stream_s = (int(packet.events["t"][-1]) + 1) / 1e6
                lag_max = max(lag_max, time.monotonic() - start - stream_s)
            if device.exhausted and packet.is_empty:
                break
        wall = time.monotonic() - start
        stats = camera.reader.stats
    expected = block_events * repeats
    return {
        "stream_s": repeats * block_us / 1e6,
        "events": received,
        "expected": expected,
        "wall_s": wall,
        "mevents_s": received / (repeats * block_us / 1e6) / 1e6,
        "lag_max_s": lag_max,
        "packets_lost": stats.packets_lost,
        "events_lost": stats.events_lost,
    }


def run(quick: bool, *, seconds: float | None = None, rate: float = 12e6) -> dict:
    """Measure the word decoder and the driver end to end; return the numbers ``main`` prints.

    Args:
        quick: 2 s end to end, a 2-block stream decoded best of 2 (else 10 s, 8 blocks, best
            of 5).
        seconds: end-to-end duration, overriding ``quick``.
        rate: events per second of the stream.

    Returns:
        ``machine``, ``rate_ev_s``, ``words_per_event``, ``decoder`` (``words``, ``seconds``,
        ``mwords_s``, ``mevents_s``), ``end_to_end`` (``stream_s``, ``events``, ``expected``,
        ``wall_s``, ``mevents_s``, ``lag_max_s``, ``packets_lost``, ``events_lost``) and
        ``targets_met`` (the decoder's words per second and the queue's overflow within
        :mod:`benchlib.targets`, no event lost end to end).
    """
    seconds = seconds or (2.0 if quick else 10.0)
    blocks = 2 if quick else 8
    block, block_events = event_block(rate, wraps=4)
    decode = bench_decoder(np.tile(block, blocks), block_events * blocks, repeats=2 if quick else 5)
    e2e = bench_end_to_end(block, block_events, seconds)
    ok = (
        USB_DECODER_MWORDS_S.met(decode["mwords_s"])
        and QUEUE_OVERFLOW.met(e2e["packets_lost"])
        and e2e["events"] == e2e["expected"]
    )
    return {
        "machine": f"{platform.platform()}, {os.cpu_count()} cores, "
        f"{platform.processor() or '?'}, python {platform.python_version()}, "
        f"numpy {np.__version__}",
        "rate_ev_s": rate,
        "words_per_event": len(block) / block_events,
        "decoder": decode,
        "end_to_end": e2e,
        "targets_met": bool(ok),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 s end to end, fewer repeats")
    parser.add_argument("--seconds", type=float, default=None, help="end-to-end duration")
    parser.add_argument("--rate", type=float, default=12e6, help="events per second")
    args = parser.parse_args(argv)
    print(f"command: {' '.join([os.path.basename(sys.executable), *sys.argv])}")
    result = run(args.quick, seconds=args.seconds, rate=args.rate)
    decode, e2e = result["decoder"], result["end_to_end"]
    print(f"machine: {result['machine']}")
    print(
        f"decoder: {decode['words'] / 1e6:.1f} M words ({result['words_per_event']:.2f} "
        f"words/event) in {decode['seconds']:.3f} s: {decode['mwords_s']:.1f} M words/s, "
        f"{decode['mevents_s']:.1f} M events/s (target {USB_DECODER_MWORDS_S.goal} M words/s)"
    )
    print(
        f"end to end: {e2e['stream_s']:.2f} s of stream at {args.rate / 1e6:.0f} M events/s "
        f"in {e2e['wall_s']:.2f} s wall; received {e2e['events']:,} of {e2e['expected']:,} "
        f"events ({e2e['mevents_s']:.2f} M events/s of stream time); max lag "
        f"{e2e['lag_max_s'] * 1000:.0f} ms; host queue overflow {e2e['packets_lost']} packets "
        f"({e2e['events_lost']} events)"
    )
    print("result: " + ("targets met" if result["targets_met"] else "TARGET MISSED"))
    return 0 if result["targets_met"] else 1


if __name__ == "__main__":
    sys.exit(main())
