"""Record an endless synthetic stream into the folder given as argument (killed by the tests)."""

import itertools
import sys
import time

import numpy as np
from session_fakes import FRAME_PERIOD_US, ListSource, frame_at, random_events

from davis_io.session.recorder import record
from davis_io.types import Packet


def endless_packets(with_frames):
    rng = np.random.default_rng(0)
    for index in itertools.count():
        t0 = index * FRAME_PERIOD_US
        yield Packet(events=random_events(rng, t0, t0 + FRAME_PERIOD_US, 2_000))
        if with_frames:
            yield Packet(frames=[frame_at(index, value=index % 1000)])
        else:
            time.sleep(0.002)


def report(status):
    print(f"frames {status.frames} events {status.events}", flush=True)


if __name__ == "__main__":
    frames = "--no-frames" not in sys.argv[2:]
    record(ListSource(endless_packets(frames)), sys.argv[1], status_callback=report)
