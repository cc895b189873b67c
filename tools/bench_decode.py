"""Benchmark: AEDAT 4.0 event decoding speed, ours against dv-processing in the same run.

The real DAVIS346 fixture's event packets are repeated (times shifted so they keep increasing)
into an LZ4 AEDAT 4.0 file of at least 5 M events, packet for packet as recorded; the decoders
read the whole file, best of N runs each, interleaved: ours as installed (LZ4 through the
system's liblz4 when it has one), ours with python-lz4 only (a system without liblz4), and
dv-processing.

    python tools/bench_decode.py [--quick] [--events N] [--repeats R]

Other tools call :func:`run`, which returns the printed numbers as a dict.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from davis_io.aedat import Aedat4Reader, Aedat4Writer
from davis_io.aedat.liblz4 import system_liblz4
from davis_io.types import Packet

FIXTURES = Path(__file__).resolve().parents[1] / "tests" / "fixtures"
FIXTURE = FIXTURES / "davis346-aestream.aedat4"


def build_file(path: Path, min_events: int) -> int:
    """Write the fixture's event packets repeated to at least ``min_events``; return the count."""
    with Aedat4Reader(FIXTURE) as reader:
        info = reader.info
        packets = [p.events for p in reader if len(p.events)]
    span = int(packets[-1]["t"][-1] - packets[0]["t"][0]) + 1
    written, shift = 0, 0
    with Aedat4Writer(path, info) as writer:
        while written < min_events:
            for events in packets:
                shifted = events.copy()
                shifted["t"] += shift
                writer.write(Packet(events=shifted))
                written += len(events)
            shift += span
    return written


def decode_ours(path: Path) -> int:
    with Aedat4Reader(path) as reader:
        return sum(len(packet.events) for packet in reader)


def decode_ours_python_lz4(path: Path) -> int:
    with Aedat4Reader(path, native_lz4=False) as reader:
        return sum(len(packet.events) for packet in reader)


def decode_dv(path: Path) -> int:
    import dv_processing as dv

    recording = dv.io.MonoCameraRecording(str(path))
    count = 0
    while (batch := recording.getNextEventBatch()) is not None:
        count += len(batch.numpy())  # hand the events to Python as our reader does
    return count


def best_rate(decode, path: Path, expected: int, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        count = decode(path)
        best = min(best, time.perf_counter() - start)
        if count != expected:
            sys.exit(f"{decode.__name__} decoded {count} events, expected {expected}")
    return expected / best


def run(
    quick: bool,
    *,
    events: int | None = None,
    repeats: int | None = None,
    command: str | None = None,
) -> dict:
    """Measure both decoders on one temporary file and return the numbers ``main`` prints.

    Args:
        quick: 5 M events, best of 3 (else 20 M events, best of 5).
        events: minimum events in the file, overriding ``quick``.
        repeats: runs per decoder, overriding ``quick``.
        command: the command line to report (default: ``bench_decode.py`` with ``--quick``).

    Returns:
        ``events``, ``file_mb``, ``repeats``, ``ours_ev_s``, ``python_lz4_ev_s`` (ours without
        liblz4), ``dv_ev_s``, ``ratio`` (ours / dv-processing), ``python_lz4_ratio``,
        ``liblz4`` (whether ours used it), ``command`` and ``machine``.
    """
    min_events = events or (5_000_000 if quick else 20_000_000)
    repeats = repeats or (3 if quick else 5)
    if command is None:
        command = " ".join(
            [Path(sys.executable).name, "tools/bench_decode.py", *(["--quick"] if quick else [])]
        )
    machine = (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "repeated.aedat4"
        total = build_file(path, min_events)
        file_mb = path.stat().st_size / 1e6
        decoders = (decode_ours, decode_ours_python_lz4, decode_dv)
        rates = {decoder: [] for decoder in decoders}
        for _ in range(repeats):  # interleave so all see the same machine load
            for decoder in decoders:
                rates[decoder].append(best_rate(decoder, path, total, 1))
    ours, fallback, theirs = (max(rates[decoder]) for decoder in decoders)
    return {
        "events": total,
        "file_mb": file_mb,
        "repeats": repeats,
        "ours_ev_s": ours,
        "python_lz4_ev_s": fallback,
        "dv_ev_s": theirs,
        "ratio": ours / theirs,
        "python_lz4_ratio": fallback / theirs,
        "liblz4": system_liblz4() is not None,
        "command": command,
        "machine": machine,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 M events, best of 3")
    parser.add_argument("--events", type=int, default=None, help="minimum events in the file")
    parser.add_argument("--repeats", type=int, default=None, help="runs per decoder")
    args = parser.parse_args()
    result = run(
        args.quick,
        events=args.events,
        repeats=args.repeats,
        command=" ".join([Path(sys.executable).name, *sys.argv]),
    )
    print(f"command: {result['command']}")
    print(f"machine: {result['machine']}")
    print(f"file: {result['events']:,} events, {result['file_mb']:.1f} MB, LZ4")
    repeats = result["repeats"]
    lz4 = "liblz4" if result["liblz4"] else "python-lz4: no liblz4 here"
    print(f"ours ({lz4}): {result['ours_ev_s'] / 1e6:8.1f} M events/s (best of {repeats})")
    print(f"ours (python-lz4):  {result['python_lz4_ev_s'] / 1e6:8.1f} M events/s")
    print(f"dv-processing:      {result['dv_ev_s'] / 1e6:8.1f} M events/s")
    print(
        f"ratio ours / dv-processing: {result['ratio']:.2f} "
        f"(python-lz4 only: {result['python_lz4_ratio']:.2f})"
    )


if __name__ == "__main__":
    main()
