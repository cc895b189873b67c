"""One writer per session: a second gets one line naming the first; a dead one's lock is free."""

import subprocess
import sys
import time

import pytest

from davis_io.session import SessionBusy, writer_lock
from davis_io.session.lock import LOCK_NAME

HOLD = (
    "import sys, time\n"
    "from davis_io.session import writer_lock\n"
    "with writer_lock(sys.argv[1], 'estimating poses'):\n"
    "    print('held', flush=True)\n"
    "    time.sleep(60)\n"
)


def test_a_second_writer_is_refused_by_name_until_the_first_dies(tmp_path):
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(SessionBusy) as busy:
            with writer_lock(tmp_path, "fitting"):
                pass
        message = str(busy.value)
        assert f"process {holder.pid} (estimating poses, since" in message
        assert "wait for it to finish or stop it" in message
    finally:
        holder.kill()  # SIGKILL: no clean-up, the lock file stays behind
        holder.wait(timeout=30)
    assert (tmp_path / LOCK_NAME).exists()
    with writer_lock(tmp_path, "fitting"):  # the kernel dropped the dead holder's lock
        with writer_lock(tmp_path, "adding bins"):  # the same process may nest
            pass
    started = time.time()
    with writer_lock(tmp_path, "fitting"):
        assert time.time() - started < 5


SHARE = (
    "import sys, time\n"
    "from davis_io.session import writer_lock\n"
    "with writer_lock(sys.argv[1], 'fitting fast-full', shared=True):\n"
    "    print('held', flush=True)\n"
    "    time.sleep(60)\n"
)


def test_fits_share_a_sessions_lock_and_keep_every_exclusive_writer_out(tmp_path):
    holder = subprocess.Popen(
        [sys.executable, "-c", SHARE, str(tmp_path)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with writer_lock(tmp_path, "fitting fast-base", shared=True):  # a second fit: fine
            pass
        with pytest.raises(SessionBusy, match=f"process {holder.pid} \\(fitting fast-full"):
            with writer_lock(tmp_path, "recording"):
                pass
        # Held shared here too, a write of this process's own must wait for the other fit.
        with writer_lock(tmp_path, "fitting", shared=True):
            with pytest.raises(SessionBusy):
                with writer_lock(tmp_path, "adding bins"):
                    pass
    finally:
        holder.kill()
        holder.wait(timeout=30)
    with writer_lock(tmp_path, "fitting", shared=True):
        with writer_lock(tmp_path, "adding bins"):  # alone now: made exclusive, then shared
            pass


def test_a_file_caught_mid_write_names_its_writer_and_without_one_the_file(
    tmp_path, aestream_aedat4
):
    from davis_io.cli import main
    from davis_io.errors import SessionError
    from davis_io.session import Session

    folder = tmp_path / "s"
    assert main(["record", "--replay", str(aestream_aedat4), "--out", str(folder)]) == 0
    h5 = folder / "session.h5"
    h5.write_bytes(h5.read_bytes()[: h5.stat().st_size // 2])  # as a reader sees a flush
    with pytest.raises(SessionError, match="HDF5 cannot read it") as damaged:
        Session.open(folder)
    assert not isinstance(damaged.value, SessionBusy)
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD.replace("estimating poses", "recording"), str(folder)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(SessionBusy, match=f"process {holder.pid} \\(recording"):
            Session.open(folder)
    finally:
        holder.kill()
        holder.wait(timeout=30)
