"""The cores davis_io's thread pools use, and a fit's --threads reaching them."""

from types import SimpleNamespace

import pytest

from davis_io import prepare
from davis_io.cores import cores_limited, usable_cores


def test_the_cores_are_those_the_process_may_run_on_unless_limited(monkeypatch):
    monkeypatch.setattr("os.sched_getaffinity", lambda _pid: {0, 2, 5})
    assert usable_cores() == 3
    with cores_limited(1):
        assert usable_cores() == 1
        with cores_limited(0):  # no limit
            assert usable_cores() == 3
        assert usable_cores() == 1
    with cores_limited(8):  # never more than there are
        assert usable_cores() == 3
    assert usable_cores() == 3


def test_preparing_a_session_keeps_its_stages_to_the_threads_given(monkeypatch, tmp_path):
    seen = []

    class Stop(Exception):
        pass

    def calibration_seen(_session, progress):
        seen.append(usable_cores())
        raise Stop

    class NoCalibration:
        width = height = 4
        manifest = SimpleNamespace(exposure_assumed_us=None)

        def __init__(self, _folder):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *_):
            return False

        def calibration(self):
            return None

    monkeypatch.setattr("os.sched_getaffinity", lambda _pid: {0, 1})
    monkeypatch.setattr(prepare, "session_calibration", calibration_seen)
    monkeypatch.setattr(prepare.Session, "open", NoCalibration)
    for threads in (1, 0):
        with pytest.raises(Stop):
            prepare.prepare_session(tmp_path, 4, lambda _line: None, threads=threads)
    assert seen == [1, 2]
    assert usable_cores() == 2  # the limit ends with the preparation
