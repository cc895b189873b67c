"""Benchmark: emulator speed (render, DVS step, and a whole default recording with its truth).

Target (issue 5): a 16-view 346x260 session with 17 sub-frames per exposure in at most 60 s.

    python tools/bench_emulator.py [--quick] [--scene room] [--views 16]

``--quick`` generates 4 views instead of 16 and times fewer renders.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np

from davis_io.emulator import DVS_PRESETS, DvsPixels, EmulatedCamera


def best_of(repeats: int, action) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


def bench_parts(camera: EmulatedCamera, repeats: int) -> float:
    """Print render and DVS step times; return the first render's time (it bakes)."""
    pose = camera.trajectory.c2w(np.array([0]))[0]
    start = time.perf_counter()
    camera.sensor_image(pose)
    bake_s = time.perf_counter() - start
    print(f"first render (bakes the visible surfaces): {bake_s:.2f} s")
    render_s = best_of(repeats, lambda: camera.sensor_image(pose))
    print(f"render 346x260 through the colour filter: {render_s * 1e3:.1f} ms (best of {repeats})")
    image = camera.sensor_image(pose)
    pixels = DvsPixels(DVS_PRESETS["noisy"], 260, 346, seed=0)
    pixels.step(image, 0)
    shifted = np.roll(image, 1, axis=1)
    clock = iter(range(2000, 10**9, 2000))

    def step() -> None:
        now = next(clock)
        pixels.step(shifted if now % 4000 else image, now)

    step_s = best_of(repeats, step)
    print(f"DVS step (noisy preset, image shifted by one pixel): {step_s * 1e3:.1f} ms")
    return bake_s


def bench_recording(camera: EmulatedCamera, bake_s: float) -> None:
    """Generate the whole recording and its truth; print the times."""
    start = time.perf_counter()
    events = frames = 0
    with camera:
        for packet in camera:
            events += len(packet.events)
            frames += len(packet.frames)
    stream_s = time.perf_counter() - start
    start = time.perf_counter()
    camera.truth  # noqa: B018 - renders the ground truth
    truth_s = time.perf_counter() - start
    config = camera.config
    print(f"recording: {config.frames} views, {frames} frames, {events} events, "
          f"{config.end_us / 1e6:.2f} s of device time, DVS step {config.dvs_step_us} µs, "
          f"{config.subframes} sub-frames per exposure")
    total_s = bake_s + stream_s + truth_s
    print(f"  first render {bake_s:.1f} s + stream {stream_s:.1f} s + truth {truth_s:.1f} s = "
          f"{total_s:.1f} s wall (target for 16 views: <= 60 s); "
          f"process CPU time so far {time.process_time():.1f} s")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 views, fewer repeats")
    parser.add_argument("--scene", default="room")
    parser.add_argument("--views", type=int, default=16)
    args = parser.parse_args(argv)
    print("command:", " ".join([sys.executable, *sys.argv]))
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"load {', '.join(f'{v:.2f}' for v in os.getloadavg())}, numpy {np.__version__}")
    camera = EmulatedCamera(args.scene, frames=4 if args.quick else args.views, test_views=8)
    bake_s = bench_parts(camera, 5 if args.quick else 20)
    bench_recording(camera, bake_s)
    return 0


if __name__ == "__main__":
    sys.exit(main())
