"""``--threads N`` bounds every CPU pool of the process, not torch's alone."""

import json
import subprocess
import sys

PROBE = """
import json, sys
import cv2, torch
from threadpoolctl import threadpool_info
from seenerf.train.threads import limit_threads
if sys.argv[1] != "untouched":
    limit_threads(int(sys.argv[1]))
print(json.dumps({
    "torch": torch.get_num_threads(),
    "blas": [pool["num_threads"] for pool in threadpool_info()],
    "opencv": cv2.getNumThreads(),
}))
"""


def _pools(count: int | str) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(count)], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


def test_one_thread_means_one_in_torch_blas_and_opencv():
    pools = _pools(1)
    assert pools["torch"] == 1 and pools["opencv"] == 1
    assert pools["blas"] and set(pools["blas"]) == {1}  # numpy's OpenBLAS is among them


def test_zero_leaves_the_defaults():
    assert _pools(0) == _pools("untouched")
