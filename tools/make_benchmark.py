"""Write the emulated benchmark sessions that the pose and trainer benchmarks score against.

Each benchmark is one built-in scene filmed by the emulated DAVIS346 with a fixed seed, so anyone
regenerates byte-identical data:

| name          | scene    | seed | colour filter | response        | exposure |
|---------------|----------|------|---------------|-----------------|----------|
| room          | room     | 1    | RGGB          | reinhard_gamma  | 0.15 s   |
| lamp          | lamp     | 2    | RGGB          | reinhard_gamma  | 0.15 s   |
| corridor      | corridor | 3    | RGGB          | reinhard_gamma  | 0.15 s   |
| room-mono     | room     | 4    | mono          | reinhard_gamma  | 0.15 s   |
| lamp-film     | lamp     | 5    | RGGB          | film            | 0.15 s   |

All use 16 training views, 8 held-out test views, the ``noisy`` DVS preset, 17 sub-frames per
exposure and the emulator's default shake. For each benchmark NAME the tool writes the session
``OUT/NAME/`` (recorded with ``davis_io.session.record``, b = 4, plus ``truth/``) and, unless
``--no-aedat``, the same stream as ``OUT/NAME.aedat4``, both from one pass of the emulator.

    python tools/make_benchmark.py --out benchmarks [--only room lamp] [--quick] [--overwrite]
                                   [--no-aedat]

``--quick`` writes 4 training and 2 test views per benchmark (a smoke test, not the benchmark).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Self

from davis_io.aedat.aedat4_write import Aedat4Writer
from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record
from davis_io.session.truth import save_truth
from davis_io.types import Packet


@dataclass(frozen=True)
class Benchmark:
    name: str
    scene: str
    seed: int
    color_filter: str = "RGGB"
    response: str = "reinhard_gamma"
    exposure_us: int = 150_000


BENCHMARKS = (
    Benchmark("room", "room", 1),
    Benchmark("lamp", "lamp", 2),
    Benchmark("corridor", "corridor", 3),
    Benchmark("room-mono", "room", 4, color_filter="mono"),
    Benchmark("lamp-film", "lamp", 5, response="film"),
)


class TeeSource:
    """A packet source that also writes every packet it yields to an AEDAT 4.0 writer."""

    def __init__(self, source: EmulatedCamera, writer: Aedat4Writer | None) -> None:
        self.source = source
        self.info = source.info
        self.writer = writer

    def __enter__(self) -> Self:
        self.source.__enter__()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.source.__exit__(exc_type, exc, tb)

    def __iter__(self) -> Iterator[Packet]:
        for packet in self.source:
            if self.writer is not None:
                self.writer.write(packet)
            yield packet


def make(benchmark: Benchmark, out: Path, *, quick: bool, overwrite: bool, aedat: bool) -> None:
    views = (4, 2) if quick else (16, 8)
    camera = EmulatedCamera(
        benchmark.scene,
        seed=benchmark.seed,
        color_filter=benchmark.color_filter,
        response=benchmark.response,
        exposure_us=benchmark.exposure_us,
        frames=views[0],
        test_views=views[1],
    )
    start = time.perf_counter()
    folder = out / benchmark.name
    if aedat:
        with Aedat4Writer(out / f"{benchmark.name}.aedat4", camera.info) as writer:
            result = record(
                TeeSource(camera, writer),
                folder,
                overwrite=overwrite,
                exposure_us=benchmark.exposure_us,
            )
    else:
        result = record(camera, folder, overwrite=overwrite, exposure_us=benchmark.exposure_us)
    save_truth(camera.truth, folder / "truth")
    manifest = result.manifest
    print(
        f"{benchmark.name}: {folder} ({result.status}, {manifest.frame_count} frames, "
        f"{manifest.event_count} events) in {time.perf_counter() - start:.1f} s"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="folder for the sessions")
    parser.add_argument(
        "--only",
        nargs="+",
        choices=[b.name for b in BENCHMARKS],
        help="write only these benchmarks",
    )
    parser.add_argument("--quick", action="store_true", help="4 + 2 views per benchmark")
    parser.add_argument("--overwrite", action="store_true", help="replace existing sessions")
    parser.add_argument("--no-aedat", action="store_true", help="skip the AEDAT 4.0 files")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    print("command:", " ".join([sys.executable, *sys.argv]))
    for benchmark in BENCHMARKS:
        if args.only is None or benchmark.name in args.only:
            make(
                benchmark,
                args.out,
                quick=args.quick,
                overwrite=args.overwrite,
                aedat=not args.no_aedat,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
