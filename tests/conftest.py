"""Shared test helpers: where the real recordings live."""

from pathlib import Path

import pytest

SHARED_DIR = Path(__file__).resolve().parents[1].parent / "shared"
FIXTURES_DIR = SHARED_DIR / "fixtures"
AESTREAM_AEDAT4 = FIXTURES_DIR / "davis346-aestream.aedat4"


@pytest.fixture
def aestream_aedat4() -> Path:
    """The real DAVIS346 AEDAT 4.0 recording described in ``shared/fixtures/README.md``."""
    if not AESTREAM_AEDAT4.exists():
        pytest.fail(
            f"fixture missing: {AESTREAM_AEDAT4} (the shared/ folder must sit beside the repo)"
        )
    return AESTREAM_AEDAT4
