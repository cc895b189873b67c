"""Record an endless synthetic stream into the folder given as argument (killed by the tests)."""

import sys

from session_fakes import ListSource, endless_packets

from davis_io.cli import end_process
from davis_io.session.recorder import RecordingError, record


def report(status):
    print(f"frames {status.frames} events {status.events}", flush=True)


if __name__ == "__main__":
    frames = "--no-frames" not in sys.argv[2:]
    try:
        record(ListSource(endless_packets(frames)), sys.argv[1], status_callback=report)
    except RecordingError as error:
        print(f"seecap: error: record: {error}", file=sys.stderr)
        end_process(1)
    end_process(0)
