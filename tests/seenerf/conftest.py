"""Tiny analytic scenes for trainer tests (seeded, a few milliseconds to build)."""

import pytest

from seenerf.data.synthetic import plane_scene


@pytest.fixture(scope="session")
def tiny_scene():
    return plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
