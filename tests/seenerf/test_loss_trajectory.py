"""A short fit at a fixed seed takes the same steps as the training loop did when the fixture
was written: structure may change, what is learned may not (``loss_trajectory.py`` writes it)."""

import json

import pytest
from loss_trajectory import FITS, FIXTURE, trajectory


@pytest.mark.parametrize("name", sorted(FITS))
def test_a_short_fit_keeps_its_loss_trajectory(name):
    expected = json.loads(FIXTURE.read_text())[name]
    got = trajectory(FITS[name])
    assert len(got) == len(expected)  # the log may show more terms; those it showed stay
    for step, (ours, theirs) in enumerate(zip(got, expected, strict=True)):
        for term, value in theirs.items():
            assert ours[term] == pytest.approx(value, rel=1e-5, abs=1e-9), (step, term)
