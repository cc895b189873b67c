"""LPIPS is optional and never downloads: without the package or the weights, it says why."""

import importlib.util

from seenerf.eval import perceptual


def test_without_the_package_lpips_is_skipped_with_the_reason(monkeypatch):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    scorer, note = perceptual.lpips_scorer()
    assert scorer is None and "lpips package is not installed" in note


def test_without_local_weights_lpips_is_skipped_naming_where_they_were_looked_for(
    monkeypatch, tmp_path
):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: object())
    scorer, note = perceptual.lpips_scorer(hub_dir=tmp_path)
    assert scorer is None
    assert str(tmp_path / "checkpoints") in note and "AlexNet" in note
