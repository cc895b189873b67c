"""Shared test helpers: where the real recordings live, and a tiny emulated session ready to fit."""

import shutil
from pathlib import Path

import pytest

from davis_io.emulator import EmulatedCamera
from davis_io.poses.truth import store_true_poses
from davis_io.session import Session
from davis_io.session.calibration import default_calibration
from davis_io.session.recorder import record
from davis_io.session.truth import save_truth

FIXTURES_DIR = Path(__file__).resolve().parent / "fixtures"
AESTREAM_AEDAT4 = FIXTURES_DIR / "davis346-aestream.aedat4"
TINY_BINS = 4


@pytest.fixture(scope="session")
def tiny_session(tmp_path_factory):
    """4 exposures of 64 x 48 pixels with the true poses and a nominal calibration."""
    folder = tmp_path_factory.mktemp("tiny") / "tiny"
    camera = EmulatedCamera(
        width=64, height=48, focal_px=52.0, frames=4, test_views=1, exposure_us=40_000, subframes=5
    )
    record(camera, folder, bins=TINY_BINS)
    save_truth(camera.truth, folder / "truth")
    store_true_poses(folder, TINY_BINS)
    with Session.open(folder) as session:
        session.write_calibration(default_calibration(0.3, "nominal, for a test"))
    return folder


@pytest.fixture
def copies(tiny_session, tmp_path):
    """``copies(name, ...)``: fresh copies of the tiny session, one folder per name."""
    return lambda *names: [shutil.copytree(tiny_session, tmp_path / name) for name in names]


@pytest.fixture
def aestream_aedat4() -> Path:
    """The real DAVIS346 AEDAT 4.0 recording described in ``tests/fixtures/README.md``."""
    if not AESTREAM_AEDAT4.exists():
        pytest.fail(f"fixture missing: {AESTREAM_AEDAT4} (tests/fixtures/ is part of the repo)")
    return AESTREAM_AEDAT4
