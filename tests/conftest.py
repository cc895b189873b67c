"""Shared test helpers: where the real recordings live."""

from pathlib import Path

import pytest

FIXTURES_DIR = Path(__file__).resolve().parent / "fixtures"
AESTREAM_AEDAT4 = FIXTURES_DIR / "davis346-aestream.aedat4"


@pytest.fixture
def aestream_aedat4() -> Path:
    """The real DAVIS346 AEDAT 4.0 recording described in ``tests/fixtures/README.md``."""
    if not AESTREAM_AEDAT4.exists():
        pytest.fail(f"fixture missing: {AESTREAM_AEDAT4} (tests/fixtures/ is part of the repo)")
    return AESTREAM_AEDAT4
