"""Benchmark: binning + h() calibration speed, and sustained recording throughput.

1. Binning: one 346x260 exposure holding 1 M random events, b = 4 and b = 6, best of N.
   Target: :data:`benchlib.targets.BINNING_S`.
2. Recording: a synthetic DAVIS346 source paced in real time at 12 M events/s (2 ms packets, a
   150 ms exposure every 200 ms, frames delivered after their readout) recorded as a live camera
   (``origin="usb"``: a full queue drops packets instead of waiting). Target: no drops.

    python tools/bench_record.py [--quick] [--rate MEV] [--seconds S] [--exposure-ms E]
                                 [--packet-ms P] [--skip-binning]

Other tools call :func:`run`, which returns the printed numbers as a dict.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from benchlib.targets import BINNING_S, DROPPED_EVENTS

from davis_io.bins import bin_exposure
from davis_io.session.recorder import record
from davis_io.types import EVENT_DTYPE, Frame, Packet, SourceInfo

WIDTH, HEIGHT = 346, 260


def random_events(rng: np.random.Generator, count: int, t0: int, t1: int) -> np.ndarray:
    events = np.empty(count, EVENT_DTYPE)
    events["t"] = np.sort(rng.integers(t0, t1, count))
    events["x"] = rng.integers(0, WIDTH, count)
    events["y"] = rng.integers(0, HEIGHT, count)
    events["p"] = rng.choice(np.array([-1, 1], np.int8), count)
    return events


def load_average() -> str:
    return ", ".join(f"{value:.2f}" for value in os.getloadavg())


def bench_binning(repeats: int) -> dict[int, float]:
    rng = np.random.default_rng(0)
    events = random_events(rng, 1_000_000, 0, 150_000)
    best = {}
    for b in (4, 6):
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            bin_exposure(events, 0, 150_000, b, WIDTH, HEIGHT)
            times.append(time.perf_counter() - start)
        best[b] = min(times)
    return best


class PacedSource:
    """Replays pre-generated 1 ms event packets in real time, with frames every interval."""

    def __init__(
        self,
        rate_ev_s: float,
        seconds: float,
        exposure_us: int,
        interval_us: int,
        packet_us: int,
        *,
        paced: bool = True,
    ):
        self.paced = paced
        self.info = SourceInfo(
            camera="DAVIS346",
            serial="BENCH",
            width=WIDTH,
            height=HEIGHT,
            origin="usb" if paced else "emulator:bench",
        )
        rng = np.random.default_rng(1)
        self.packet_us = packet_us
        per_packet = int(rate_ev_s * packet_us / 1e6)
        self.pool = [random_events(rng, per_packet, 0, packet_us) for _ in range(16)]
        self.image = rng.integers(100, 900, (HEIGHT, WIDTH)).astype(np.uint16)
        self.packets = int(seconds * 1e6 / packet_us)
        self.exposure_us, self.interval_us = exposure_us, interval_us
        self.late_s = 0.0

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return None

    def _frame(self, index: int) -> Frame:
        start = index * self.interval_us + 10_000
        return Frame(
            self.image,
            start,
            start + self.exposure_us,
            start - 5_000,
            start + self.exposure_us + 10_000,
        )

    def __iter__(self):
        begin = time.perf_counter()
        next_frame = 0
        for index in range(self.packets):
            due = begin + index * self.packet_us / 1e6
            wait = due - time.perf_counter() if self.paced else 0.0
            if wait > 0:
                time.sleep(wait)
            elif self.paced:
                self.late_s = max(self.late_s, -wait)
            events = self.pool[index % len(self.pool)].copy()
            events["t"] += index * self.packet_us
            frames = []
            end_us = (index + 1) * self.packet_us
            while self._frame(next_frame).readout_end_us < end_us:
                frames.append(self._frame(next_frame))
                next_frame += 1
            yield Packet(events=events, frames=frames)


def bench_recording(
    rate: float,
    seconds: float,
    exposure_us: int,
    packet_us: int,
    folder: Path,
    *,
    paced: bool = True,
) -> dict:
    source = PacedSource(rate, seconds, exposure_us, exposure_us + 50_000, packet_us, paced=paced)
    fills = []
    cpu_before = resource.getrusage(resource.RUSAGE_SELF)
    start = time.perf_counter()
    result = record(
        source,
        folder / "session",
        bins=4,
        overwrite=True,
        status_callback=lambda status: fills.append(status.queue_fill),
    )
    wall = time.perf_counter() - start
    cpu_after = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (cpu_after.ru_utime - cpu_before.ru_utime) + (cpu_after.ru_stime - cpu_before.ru_stime)
    manifest = result.manifest
    size = (folder / "session" / "session.h5").stat().st_size
    return {
        "events": manifest.event_count,
        "frames": manifest.frame_count,
        "dropped_events": manifest.drops.total_events,
        "dropped_packets": manifest.drops.queue_packets,
        "wall_s": wall,
        "events_per_s": manifest.event_count / wall,
        "cpu_s": cpu,
        "max_queue_fill": max(fills, default=0.0),
        "source_late_ms": source.late_s * 1000,
        "mb": size / 1e6,
    }


def run(
    quick: bool,
    *,
    rate_mev_s: float = 12.0,
    seconds: float | None = None,
    exposure_ms: float = 150.0,
    packet_ms: float = 2.0,
    skip_binning: bool = False,
) -> dict:
    """Measure binning and recording; return the numbers ``main`` prints.

    Args:
        quick: 3 s of recording, binning best of 3 (else 20 s, best of 7).
        rate_mev_s: stream rate, M events/s.
        seconds: recording length, overriding ``quick``.
        exposure_ms: APS exposure, ms (a frame every exposure + 50 ms).
        packet_ms: device time per packet, ms.
        skip_binning: only the recording part (``binning_s`` is then empty).

    Returns:
        ``machine``, ``load_average_before``, ``settings`` (the arguments above, resolved),
        ``binning_s`` (``{"b4": s, "b6": s}``, best times for 1 M events), ``capacity`` and
        ``recording`` (each :func:`bench_recording`'s dict: unpaced with a waiting queue, and
        paced in real time as a live camera) and ``targets_met`` (binning under 0.5 s, no
        drops).
    """
    seconds = seconds or (3.0 if quick else 20.0)
    machine = (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"{platform.system()} {platform.release()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}"
    )
    load_before = load_average()
    best = {} if skip_binning else bench_binning(3 if quick else 7)
    settings = (rate_mev_s * 1e6, seconds, int(exposure_ms * 1000), int(packet_ms * 1000))
    with tempfile.TemporaryDirectory() as folder:
        capacity = bench_recording(*settings, Path(folder), paced=False)
    with tempfile.TemporaryDirectory() as folder:
        stats = bench_recording(*settings, Path(folder))
    ok = DROPPED_EVENTS.met(stats["dropped_events"]) and all(map(BINNING_S.met, best.values()))
    return {
        "machine": machine,
        "load_average_before": load_before,
        "settings": {
            "rate_mev_s": rate_mev_s,
            "seconds": seconds,
            "exposure_ms": exposure_ms,
            "packet_ms": packet_ms,
        },
        "binning_s": {f"b{b}": value for b, value in best.items()},
        "capacity": capacity,
        "recording": stats,
        "targets_met": bool(ok),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short run (3 s of recording)")
    parser.add_argument("--rate", type=float, default=12.0, help="M events/s (default 12)")
    parser.add_argument("--seconds", type=float, default=None, help="recording length")
    parser.add_argument("--exposure-ms", type=float, default=150.0, help="APS exposure")
    parser.add_argument(
        "--packet-ms",
        type=float,
        default=2.0,
        help="device time per packet (a 128 KiB USB transfer is ~2.5 ms at 12 M/s)",
    )
    parser.add_argument("--skip-binning", action="store_true", help="only the recording part")
    args = parser.parse_args()
    print(f"command: {' '.join([sys.executable, *sys.argv])}")
    result = run(
        args.quick,
        rate_mev_s=args.rate,
        seconds=args.seconds,
        exposure_ms=args.exposure_ms,
        packet_ms=args.packet_ms,
        skip_binning=args.skip_binning,
    )
    seconds = result["settings"]["seconds"]
    print(f"machine: {result['machine']}; load average before: {result['load_average_before']}")
    for name, value in result["binning_s"].items():
        verdict = "ok" if BINNING_S.met(value) else "TOO SLOW"
        print(
            f"binning + h() of 1 M events, 346x260, b={name[1:]}: {value:.3f} s "
            f"(target {BINNING_S.goal} s) {verdict}"
        )
    capacity, stats = result["capacity"], result["recording"]
    print(
        f"capacity (unpaced, waiting queue): {capacity['events_per_s'] / 1e6:.2f} M events/s "
        f"wall; {capacity['cpu_s'] / seconds:.2f} CPU-seconds per second of a "
        f"{args.rate:g} M events/s stream"
    )
    print(
        f"recording {args.rate:g} M events/s in {args.packet_ms:g} ms packets for "
        f"{seconds:g} s, exposure "
        f"{args.exposure_ms:g} ms: {stats['events']} events, {stats['frames']} frames, "
        f"{stats['events_per_s'] / 1e6:.2f} M events/s over {stats['wall_s']:.1f} s wall, "
        f"{stats['cpu_s']:.1f} s CPU, {stats['mb']:.0f} MB, max queue fill "
        f"{stats['max_queue_fill']:.0%}, source late by up to {stats['source_late_ms']:.0f} ms"
    )
    drops_ok = DROPPED_EVENTS.met(stats["dropped_events"])
    print(
        f"drops: {stats['dropped_events']} events in {stats['dropped_packets']} packets "
        f"(target {DROPPED_EVENTS.goal}) {'ok' if drops_ok else 'DROPS'}"
    )
    return 0 if result["targets_met"] else 1


if __name__ == "__main__":
    sys.exit(main())
