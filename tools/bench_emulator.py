"""Benchmark: emulator speed (render, DVS step, and a whole default recording with its truth).

Target (issue 5): a 16-view 346x260 session with 17 sub-frames per exposure in at most 60 s.

    python tools/bench_emulator.py [--quick] [--scene room] [--views 16]

``--quick`` generates 4 views instead of 16 and times fewer renders. Other tools call
:func:`run`, which returns the printed numbers as a dict.
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


def bench_parts(camera: EmulatedCamera, repeats: int) -> dict:
    """Time the first render (it bakes), a render and a DVS step; seconds in a dict."""
    pose = camera.trajectory.c2w(np.array([0]))[0]
    start = time.perf_counter()
    camera.sensor_image(pose)
    bake_s = time.perf_counter() - start
    render_s = best_of(repeats, lambda: camera.sensor_image(pose))
    image = camera.sensor_image(pose)
    pixels = DvsPixels(DVS_PRESETS["noisy"], 260, 346, seed=0)
    pixels.step(image, 0)
    shifted = np.roll(image, 1, axis=1)
    clock = iter(range(2000, 10**9, 2000))

    def step() -> None:
        now = next(clock)
        pixels.step(shifted if now % 4000 else image, now)

    return {
        "bake_s": bake_s,
        "render_s": render_s,
        "dvs_step_s": best_of(repeats, step),
        "repeats": repeats,
    }


def bench_recording(camera: EmulatedCamera) -> dict:
    """Generate the whole recording and its truth; counts and seconds in a dict."""
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
    return {
        "views": config.frames,
        "frames": frames,
        "events": events,
        "device_s": config.end_us / 1e6,
        "dvs_step_us": config.dvs_step_us,
        "subframes": config.subframes,
        "stream_s": stream_s,
        "truth_s": truth_s,
    }


def run(quick: bool, *, scene: str = "room", views: int = 16) -> dict:
    """Time the emulator's parts and a whole recording; return the numbers ``main`` prints.

    Args:
        quick: 4 views and 5 repeats of each part (else ``views`` and 20 repeats).
        scene: built-in scene.
        views: training views of the recording (8 held-out views are rendered too).

    Returns:
        ``machine``, ``parts`` (:func:`bench_parts`), ``recording`` (:func:`bench_recording`),
        ``total_s`` (first render + stream + truth) and ``process_cpu_s`` (this process's CPU
        time at the end).
    """
    machine = (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"load {', '.join(f'{v:.2f}' for v in os.getloadavg())}, numpy {np.__version__}"
    )
    camera = EmulatedCamera(scene, frames=4 if quick else views, test_views=8)
    parts = bench_parts(camera, 5 if quick else 20)
    recording = bench_recording(camera)
    total_s = parts["bake_s"] + recording["stream_s"] + recording["truth_s"]
    return {
        "machine": machine,
        "parts": parts,
        "recording": recording,
        "total_s": total_s,
        "process_cpu_s": time.process_time(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 views, fewer repeats")
    parser.add_argument("--scene", default="room")
    parser.add_argument("--views", type=int, default=16)
    args = parser.parse_args(argv)
    print("command:", " ".join([sys.executable, *sys.argv]))
    result = run(args.quick, scene=args.scene, views=args.views)
    parts, recording = result["parts"], result["recording"]
    print(f"machine: {result['machine']}")
    print(f"first render (bakes the visible surfaces): {parts['bake_s']:.2f} s")
    print(
        f"render 346x260 through the colour filter: {parts['render_s'] * 1e3:.1f} ms "
        f"(best of {parts['repeats']})"
    )
    print(
        f"DVS step (noisy preset, image shifted by one pixel): {parts['dvs_step_s'] * 1e3:.1f} ms"
    )
    print(
        f"recording: {recording['views']} views, {recording['frames']} frames, "
        f"{recording['events']} events, {recording['device_s']:.2f} s of device time, DVS step "
        f"{recording['dvs_step_us']} µs, {recording['subframes']} sub-frames per exposure"
    )
    print(
        f"  first render {parts['bake_s']:.1f} s + stream {recording['stream_s']:.1f} s + truth "
        f"{recording['truth_s']:.1f} s = {result['total_s']:.1f} s wall (target for 16 views: "
        f"<= 60 s); process CPU time {result['process_cpu_s']:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
