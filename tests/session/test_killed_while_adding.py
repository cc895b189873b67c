"""A process killed while it adds bins or poses to a session leaves it readable, or says how."""

import signal
import subprocess
import sys
import textwrap

import pytest

from davis_io.emulator import EmulatedCamera
from davis_io.errors import SessionError
from davis_io.session import Session
from davis_io.session.recorder import record

SMALL = dict(width=32, height=24, focal_px=26.0, frames=2, test_views=0, exposure_us=20_000)

HOLD_OPEN = textwrap.dedent(
    """
    import sys, time
    from davis_io.session import Session
    with Session.open(sys.argv[1]) as session:
        with session._writable():
            print("open", flush=True)
            time.sleep(60)
    """
)


def _hold_open_then(folder, signal_number):
    process = subprocess.Popen(
        [sys.executable, "-c", HOLD_OPEN, str(folder)], stdout=subprocess.PIPE, text=True
    )
    assert process.stdout.readline().strip() == "open"
    process.send_signal(signal_number)
    return process.wait(timeout=60)


@pytest.fixture
def session_folder(tmp_path):
    return record(EmulatedCamera("room", seed=3, **SMALL), tmp_path / "s").folder


def test_sigterm_while_the_file_is_open_for_writing_closes_it(session_folder):
    assert _hold_open_then(session_folder, signal.SIGTERM) == 128 + signal.SIGTERM
    with Session.open(session_folder) as session:
        assert not session.needs_repair and session.frame_count == 2


def test_a_file_left_open_by_sigkill_names_the_fix(session_folder):
    assert _hold_open_then(session_folder, signal.SIGKILL) == -signal.SIGKILL
    with pytest.raises(SessionError, match="h5clear -s .*session.h5"):
        Session.open(session_folder)
