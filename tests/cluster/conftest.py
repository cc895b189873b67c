"""A tiny emulated session ready to fit, copies of it, and one local Ray instance per module."""

import faulthandler
import shutil

import pytest

from davis_io.emulator import EmulatedCamera
from davis_io.poses.truth import store_true_poses
from davis_io.session import Session
from davis_io.session.calibration import default_calibration
from davis_io.session.recorder import record
from davis_io.session.truth import save_truth

BINS = 4


@pytest.fixture(scope="session")
def tiny_session(tmp_path_factory):
    """4 exposures of 64 x 48 pixels with the true poses and a nominal calibration."""
    folder = tmp_path_factory.mktemp("cluster") / "tiny"
    camera = EmulatedCamera(
        width=64, height=48, focal_px=52.0, frames=4, test_views=1, exposure_us=40_000, subframes=5
    )
    record(camera, folder, bins=BINS)
    save_truth(camera.truth, folder / "truth")
    store_true_poses(folder, BINS)
    with Session.open(folder) as session:
        session.write_calibration(default_calibration(0.3, "nominal, for a test"))
    return folder


@pytest.fixture
def copies(tiny_session, tmp_path):
    """``copies(name, ...)``: fresh copies of the tiny session, one folder per name."""
    return lambda *names: [shutil.copytree(tiny_session, tmp_path / name) for name in names]


@pytest.fixture(scope="module")
def local_ray():
    """Ray on this machine with 2 CPUs, loopback only; the module dies after 15 minutes."""
    from seenerf.cli.cluster import ray_connection

    faulthandler.dump_traceback_later(900, exit=True)
    try:
        with ray_connection("local", cpus=2) as ray:
            yield ray
    finally:
        faulthandler.cancel_dump_traceback_later()
