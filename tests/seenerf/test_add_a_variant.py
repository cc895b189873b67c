"""The README's "how to add a variant", followed: a toy variant with a method of its own."""

import pytest
import torch

from seenerf.errors import OptionError
from seenerf.model.config import FitConfig
from seenerf.model.variants import VARIANTS, Variant
from seenerf.train.methods import METHODS, LossTerm, RecordingMethod, Step, make_method
from seenerf.train.trainer import Trainer


class FramesOnly(RecordingMethod):
    """The recorded frames alone: the events are read into batches but never compared."""

    def step(self, generator: torch.Generator) -> Step:
        full = super().step(generator)
        kept = [term for term in full.terms if term.name not in ("events", "spans")]
        return Step([*kept, LossTerm("toy", 0.0, torch.zeros(()))], full.rays, full.samples)


def test_a_toy_variant_trains_through_its_own_method(monkeypatch, tiny_scene):
    monkeypatch.setitem(METHODS, "frames-only", FramesOnly)
    monkeypatch.setitem(
        VARIANTS, "toy", Variant("frames only, events unused", method="frames-only")
    )
    config = FitConfig.of(variant="toy", steps=4, batch_pixels=8, warm_steps=2, threads=1)
    trainer = Trainer(make_method(tiny_scene, config), log=lambda line: None)
    assert isinstance(trainer.method, FramesOnly)
    before = [p.detach().clone() for p in trainer.model.renderer.parameters()]
    trainer.train()
    assert set(trainer.last_terms) == {"ldr", "anchor", "smoothness", "toy"}
    after = list(trainer.model.renderer.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after, strict=True))


def test_a_variant_naming_no_method_is_refused(monkeypatch, tiny_scene):
    monkeypatch.setitem(VARIANTS, "lost", Variant("names a method nobody wrote", method="nobody"))
    with pytest.raises(OptionError, match="unknown method 'nobody'; choose one of: recording"):
        make_method(tiny_scene, FitConfig.of(variant="lost", steps=1))
