"""``seecap`` turns numpy's huge-page advice off before numpy loads, unless the user set it."""

import os
import subprocess
import sys

PROBE = (
    "import os, sys\n"
    "import davis_io.cli\n"
    "print('numpy' in sys.modules, os.environ['NUMPY_MADVISE_HUGEPAGE'])\n"
)


def _probe(**setting: str) -> str:
    env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"} | setting
    done = subprocess.run(
        [sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True
    )
    return done.stdout.strip()


def test_the_entry_point_turns_the_advice_off_before_numpy_is_imported():
    assert _probe() == "False 0"


def test_a_users_own_setting_stands():
    assert _probe(NUMPY_MADVISE_HUGEPAGE="1") == "False 1"
