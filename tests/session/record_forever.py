"""Record an endless synthetic stream into the folder given as argument (killed by the tests)."""

import sys

from session_fakes import ListSource, endless_packets

from davis_io.session.recorder import record


def report(status):
    print(f"frames {status.frames} events {status.events}", flush=True)


if __name__ == "__main__":
    frames = "--no-frames" not in sys.argv[2:]
    record(ListSource(endless_packets(frames)), sys.argv[1], status_callback=report)
