import math

import numpy as np
import pytest
import torch

from seenerf.data.synthetic import plane_scene
from seenerf.errors import CheckpointError, ConfigError
from seenerf.model.config import FitConfig
from seenerf.model.presets import PRESETS
from seenerf.model.variants import VARIANTS
from seenerf.train.builder import size_field
from seenerf.train.fit import clipped_events_note
from seenerf.train.losses import NOISE_REFERENCE, event_loss, exposure_loss, noise_even
from seenerf.train.methods import frame_scale, make_method
from seenerf.train.trainer import Trainer


def _config(**overrides):
    values = {"steps": 3, "batch_pixels": 6, "warm_steps": 2, "validation_share": 0.1, "threads": 2}
    values.update(overrides)
    return FitConfig.of(**values)


def _parameters_changed(trainer, before):
    after = [p.detach().clone() for p in trainer.model.parameters()]
    return any(not torch.equal(a, b) for a, b in zip(before, after, strict=True))


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_every_preset_trains_a_few_steps(preset, tiny_scene):
    trainer = Trainer(make_method(tiny_scene, _config(preset=preset)), log=lambda line: None)
    before = [p.detach().clone() for p in trainer.model.parameters()]
    summary = trainer.train()
    assert summary.steps == 3 and summary.skipped_steps == 0
    assert _parameters_changed(trainer, before)


@pytest.mark.parametrize("variant", sorted(set(VARIANTS) - {"multi-exposure"}))
def test_every_variant_trains_a_few_steps(variant, tiny_scene):
    trainer = Trainer(make_method(tiny_scene, _config(variant=variant)), log=lambda line: None)
    before = [p.detach().clone() for p in trainer.model.parameters()]
    summary = trainer.train()
    assert summary.steps == 3 and summary.skipped_steps == 0
    assert _parameters_changed(trainer, before)


@pytest.mark.parametrize(("share", "drawn"), [(0.0, 0), (0.5, 3)])
def test_spans_between_frames_are_a_term_of_their_own_when_asked(share, drawn, tiny_scene):
    config = _config(span_share=share, steps=2)
    trainer = Trainer(make_method(tiny_scene, config), log=lambda line: None)
    assert trainer.method.spans == drawn  # half the batch of 6 pixels
    trainer.train()
    assert ("spans" in trainer.last_terms) == bool(drawn)
    if drawn:
        # the plane's ideal leads and a field that starts flat: the change is missed
        assert 0.0 < trainer.last_terms["spans"] < 1e3


@pytest.mark.parametrize(
    ("preset", "stated", "used"),
    [
        ("fast", None, 0.001),
        ("balanced", None, 0.001),
        ("paper", None, 0.005),
        ("fast", 0.02, 0.02),
        ("paper", 0.0, 0.0),
    ],
)
def test_the_event_weight_is_the_presets_unless_one_is_stated(preset, stated, used, tiny_scene):
    config = _config(preset=preset, event_weight=stated)
    trainer = Trainer(make_method(tiny_scene, config), log=lambda line: None)
    assert trainer.preset.event_weight == used
    with pytest.raises(ConfigError, match="--event-weight -0.1 is out of range"):
        FitConfig.of(event_weight=-0.1)


def test_frames_measured_linear_get_the_linear_response_unless_another_is_asked():
    from seenerf.sensors.rgb_crf import LinearCrf, MonotoneCrf, PowerCrf, RgbCrf

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    scene.linear_levels = (0.02, 0.9)
    model = make_method(scene, _config()).model  # response "auto" by default
    assert isinstance(model.crf, LinearCrf) and model.crf.black == 0.02
    assert isinstance(make_method(scene, _config(response="learned")).model.crf, RgbCrf)
    assert isinstance(make_method(scene, _config(variant="power-crf")).model.crf, PowerCrf)
    trainer = Trainer(make_method(scene, _config()), log=lambda line: None)
    assert trainer.train().skipped_steps == 0
    assert isinstance(make_method(scene, _config(response="monotone")).model.crf, MonotoneCrf)
    scene.linear_levels = None
    assert isinstance(make_method(scene, _config()).model.crf, RgbCrf)


@pytest.mark.parametrize(
    ("settled", "expected"),
    [
        # Every point settled: the mean of the bins' squared errors 0, 1, 1, 0.
        ([1, 1, 1, 1, 1], 2 / 4),
        # Bins 1 and 2 compared as one span: their errors +1 and -1 cancel.
        ([1, 1, 0, 1, 1], 0.0),
        # Bins 0-1 as one span (error 1), bin 2 alone (1), bin 3 left out (its end unsettled).
        ([1, 0, 1, 1, 0], 2 / 4),
        # Nothing settled before the last point: no span has two settled ends.
        ([0, 0, 0, 0, 1], 0.0),
        # Only the ends settled (a lone frame's whole exposure): one span, error 2 - 2 = 0.
        ([1, 0, 0, 0, 1], 0.0),
    ],
)
def test_event_loss_compares_counts_between_settled_points(settled, expected):
    predicted = torch.tensor([[1.0, 2.0, 3.0, 4.0]])
    measured = torch.tensor([[1.0, 1.0, 4.0, 4.0]])
    loss = event_loss(predicted, measured, torch.tensor([settled], dtype=torch.bool))
    assert float(loss) == pytest.approx(expected)


def test_event_loss_weighs_each_pixels_spans_by_its_weight():
    predicted = torch.tensor([[1.0, 2.0], [0.0, 3.0]])
    measured = torch.tensor([[0.0, 0.0], [0.0, 0.0]])
    settled = torch.ones((2, 3), dtype=torch.bool)
    # Squared errors 1 + 4 (row 0) and 0 + 9 (row 1), weighted 2 and 0.5: (10 + 4.5) / 4.
    loss = event_loss(predicted, measured, settled, torch.tensor([2.0, 0.5]))
    assert float(loss) == pytest.approx(14.5 / 4)
    assert float(event_loss(predicted, measured, settled)) == pytest.approx(14 / 4)


def test_exposure_loss_compares_each_lone_pixels_whole_exposure():
    predicted = torch.tensor([[1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])
    measured = torch.tensor([[4.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    settled = torch.ones((4, 4), dtype=torch.bool)
    settled[2, 3] = False  # row 2 had not settled at the exposure's end: no span
    lone = torch.tensor([True, True, True, False])  # row 3 is not lone
    # Row 0's bins err by -3, 2, 3 but its exposure by 2; row 1's by 6: (4 + 36) / 12.
    loss = exposure_loss(predicted, measured, settled, lone)
    assert float(loss) == pytest.approx(40 / 12)
    weighted = exposure_loss(predicted, measured, settled, lone, torch.tensor([3.0, 0.5, 1, 1]))
    assert float(weighted) == pytest.approx((3 * 4 + 0.5 * 36) / 12)
    assert float(exposure_loss(predicted[:0], measured[:0], settled[:0], lone[:0])) == 0.0


def test_noise_even_scale_evens_shot_and_read_noise():
    # Values 0.002 and 0.5 above black with variance 1e-4 x (v - black) + 2e-7 (offset
    # 0.002): plain standard deviations 6.3e-4 and 7.1e-3, 11x apart; on the noise-even scale
    # they agree.
    black, gain, floor = 0.03, 1e-4, 2e-7
    generator = torch.Generator().manual_seed(0)
    spreads = []
    for above in (0.002, 0.5):
        sd = math.sqrt(gain * above + floor)
        values = black + above + sd * torch.randn(200_000, generator=generator, dtype=torch.float64)
        spreads.append(float(noise_even(values, black, floor / gain).std()))
    assert spreads[0] == pytest.approx(spreads[1], rel=0.1)
    # The slope is 1 at NOISE_REFERENCE above black: there the plain error's weight is kept.
    at = torch.tensor(
        [black + NOISE_REFERENCE - 1e-6, black + NOISE_REFERENCE + 1e-6], dtype=torch.float64
    )
    slope = float(torch.diff(noise_even(at, black, 0.002))) / 2e-6
    assert slope == pytest.approx(1.0, rel=1e-6)


def test_linear_frames_of_measured_noise_are_compared_on_the_noise_even_scale():
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    values = torch.tensor([0.03, 0.1, 0.6])
    assert frame_scale(scene, _config())(values) is values  # not linear: the values
    scene.linear_levels, scene.noise_offset = (0.02, 0.9), 0.003
    expected = 2 * math.sqrt(NOISE_REFERENCE + 0.003) * torch.sqrt(values - 0.02 + 0.003)
    torch.testing.assert_close(frame_scale(scene, _config())(values), expected)
    assert frame_scale(scene, _config(frame_noise=False))(values) is values
    scene.noise_offset = 0.0  # noise not measured
    assert frame_scale(scene, _config())(values) is values


@pytest.mark.parametrize(
    ("preset", "measured", "linear", "factor"),
    [
        ("fast", True, True, 5.0),
        ("paper", True, True, None),  # as published
        ("fast", False, True, None),  # thresholds assumed
        ("fast", True, False, None),  # a learned response says how far above its clip level
    ],
)
def test_events_weigh_more_where_their_frame_clipped(preset, measured, linear, factor):
    scene = plane_scene(height=8, width=10, frames=2, b=2, test_views=0)
    scene.clip_level, scene.thresholds_measured = 0.8, measured
    scene.linear_levels = (0.02, 0.8) if linear else None
    scene.ldr[0, 0] = 0.79  # within the margin below the clip level: clipped
    scene.ldr[0, 1] = 0.75  # below it: not
    method = make_method(scene, _config(preset=preset))
    batch = method.frames.batch(torch.zeros(20, dtype=torch.long), torch.arange(20))
    weights = method.event_weights(batch.ldr)
    # a span's events weigh the factor where either of its frames clipped
    spans = method.event_weights(torch.tensor([[0.5, 0.79], [0.75, 0.5], [0.81, 0.79]]))
    if factor is None:
        assert weights is None and spans is None
    else:
        expected = torch.tensor([factor] * 10 + [1.0] * 10)
        torch.testing.assert_close(weights, expected)
        torch.testing.assert_close(spans, torch.tensor([factor, 1.0, factor]))


def test_the_fit_says_what_it_does_with_the_events_of_clipped_pixels():
    scene = plane_scene(height=8, width=10, frames=2, b=2, test_views=0)
    scene.clip_level, scene.ldr[:] = 0.8, 0.5
    scene.ldr[0, :2] = 0.8  # 20 of 160 values
    note = clipped_events_note(make_method(scene, _config()))
    assert note.endswith("their events weigh as the others', the response telling how far above")
    scene.linear_levels = (0.02, 0.8)
    note = clipped_events_note(make_method(scene, _config()))
    assert note.startswith("12.5% of the frames' pixels clipped (at 0.800): their events weigh 5x")
    scene.thresholds_measured = False
    assert "weigh as the others'" in clipped_events_note(make_method(scene, _config()))
    scene.ldr[:] = 0.5
    assert clipped_events_note(make_method(scene, _config())) == ""


@pytest.mark.parametrize(
    ("stretch", "lone_exposure_spans", "expected"),
    [([0, 1, 2], True, True), ([0, 1, 2], False, False), ([0, 0, 0], True, False)],
)
def test_lone_frames_add_their_whole_exposures_to_the_loss(stretch, lone_exposure_spans, expected):
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    scene.lead, scene.stretch = np.zeros((3, 8, 10), np.float32), np.array(stretch)
    config = _config(lone_exposure_spans=lone_exposure_spans)
    method = make_method(scene, config)
    step = method.step(torch.Generator().manual_seed(0))
    terms = {term.name: term for term in step.terms}
    assert ("exposures" in terms) is expected
    if expected:
        # Over a whole exposure of two bins the bins' errors add: (r1 + r2)^2 <= 2 (r1^2 + r2^2).
        assert terms["exposures"].weight == terms["events"].weight
        assert 0 < float(terms["exposures"].value) <= 2 * float(terms["events"].value)


def test_multi_exposure_needs_and_uses_several_exposures(tiny_scene):
    with pytest.raises(ConfigError, match="at least two exposures"):
        make_method(tiny_scene, _config(variant="multi-exposure"))
    scene = plane_scene(
        height=8, width=10, frames=3, b=2, exposure_s=np.array([0.004, 0.016, 0.064])
    )
    summary = Trainer(
        make_method(scene, _config(variant="multi-exposure")), log=lambda line: None
    ).train()
    assert summary.steps == 3


def test_oracle_needs_truth(tiny_scene):
    scene = plane_scene(height=8, width=10, frames=3, b=2)
    scene.truth = None
    with pytest.raises(ConfigError, match="ground truth"):
        make_method(scene, _config(variant="oracle"))


def test_oracle_validation_scores_its_own_sharp_hdr_supervision():
    scene = plane_scene(height=24, width=32, frames=4, b=2, test_views=1)
    trainer = Trainer(make_method(scene, _config(variant="oracle", steps=250, batch_pixels=128)))
    before = trainer.validation_psnr()
    trainer.train()
    after = trainer.validation_psnr()
    # The tone-mapped HDR of held-out truth pixels: poor at the start, good after training
    # (scoring the oracle's untrained CRF instead stays near 9 dB throughout); 37.6 dB after 250
    # steps of 128 pixels, in half the time of 200 steps of the preset's 512 (33.9 dB).
    assert before < 15.0 < 30.0 < after


def test_unknown_names_list_the_known_ones():
    with pytest.raises(ConfigError, match="full"):
        _config(variant="nope")
    with pytest.raises(ConfigError, match="fast"):
        _config(preset="nope")


def test_field_resolution_follows_the_pixel_span_within_its_bounds():
    fast = PRESETS["fast"]
    assert size_field(fast, 150.4).field_args["resolution"] == 150
    assert size_field(fast, 30.0).field_args["resolution"] == 48
    assert size_field(fast, 9000.0).field_args["resolution"] == fast.max_resolution
    assert size_field(PRESETS["paper"], 150.4) is PRESETS["paper"]


def test_killed_fit_resumes_in_place(tiny_scene, tmp_path):
    Trainer(make_method(tiny_scene, _config(steps=2)), tmp_path, log=lambda line: None).train()
    lines = []
    resumed = Trainer(make_method(tiny_scene, _config(steps=5)), tmp_path, log=lines.append)
    assert resumed.train().steps == 5
    assert any("resuming at step 2" in line for line in lines)
    with pytest.raises(CheckpointError, match="--fresh"):
        Trainer(make_method(tiny_scene, _config(steps=5, seed=1)), tmp_path).train()


def test_damaged_checkpoint_is_a_typed_error(tiny_scene, tmp_path):
    (tmp_path / "checkpoint.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="not a readable"):
        Trainer(make_method(tiny_scene, _config()), tmp_path).train()


def test_checkpoint_of_another_model_is_a_typed_error(tiny_scene, tmp_path):
    from seenerf.train.checkpoint import load_model_state

    Trainer(make_method(tiny_scene, _config(steps=1)), tmp_path, log=lambda line: None).train()
    other = make_method(tiny_scene, _config(variant="base")).model
    with pytest.raises(CheckpointError, match=r"(?s)do not fit this version's model.*--fresh"):
        load_model_state(tmp_path / "checkpoint.pt", other)


def test_time_budget_stops_training(tiny_scene):
    summary = Trainer(
        make_method(tiny_scene, _config(steps=10_000, time_budget_s=0.5)),
        log=lambda line: None,
    ).train()
    assert summary.stopped == "budget" and summary.steps < 10_000


def _field_lr_at(trainer, steps, elapsed_s):
    trainer.summary.steps, trainer.summary.elapsed_s = steps, elapsed_s
    trainer._set_learning_rate()
    return trainer.optimizer.param_groups[0]["lr"]


def test_learning_rate_falls_with_the_steps_of_a_run_without_budget(tiny_scene):
    trainer = Trainer(make_method(tiny_scene, _config(steps=6000)), log=lambda line: None)
    decay, base = trainer.preset.lr_decay_steps, trainer.preset.lr
    assert _field_lr_at(trainer, 0, 0.0) == pytest.approx(base)
    assert _field_lr_at(trainer, 3000, 1e6) == pytest.approx(base * 0.1 ** (3000 / decay))


def test_a_run_its_budget_stops_first_anneals_only_as_far_as_its_steps(tiny_scene):
    # 100 s budget, 60 s already spent on poses: 40 s of training is the whole run.
    trainer = Trainer(
        make_method(tiny_scene, _config(steps=6000, time_budget_s=100.0)),
        log=lambda line: None,
        spent_s=60.0,
    )
    decay, base = trainer.preset.lr_decay_steps, trainer.preset.lr
    assert trainer.progress() == 0.0
    assert _field_lr_at(trainer, 600, 20.0) == pytest.approx(base * 0.1 ** (600 / decay))
    assert trainer.progress() == pytest.approx(0.5)
    assert _field_lr_at(trainer, 1200, 40.0) == pytest.approx(base * 0.1 ** (1200 / decay))
    assert _field_lr_at(trainer, 4500, 10.0) == pytest.approx(base * 0.1 ** (4500 / decay))


def test_a_budget_without_a_step_count_runs_past_the_presets_steps(tiny_scene):
    trainer = Trainer(
        make_method(tiny_scene, _config(steps=None, time_budget_s=100.0)),
        log=lambda line: None,
        spent_s=60.0,
    )
    steps, decay, base = trainer.preset.steps, trainer.preset.lr_decay_steps, trainer.preset.lr
    assert trainer.total_steps == math.inf  # the budget or a plateau ends it
    # The steps taken set the rate, as in a run of that many steps ...
    assert _field_lr_at(trainer, steps // 4, 20.0) == pytest.approx(
        base * 0.1 ** (steps / 4 / decay)
    )
    # ... but it never falls faster than the preset's decay spread over the budget: at half the
    # 40 s, half of it, whatever the step; at the end the whole of it, even far past its steps.
    assert _field_lr_at(trainer, 2 * steps, 20.0) == pytest.approx(
        base * 0.1 ** (steps / 2 / decay)
    )
    assert _field_lr_at(trainer, 3 * steps, 40.0) == pytest.approx(base * 0.1 ** (steps / decay))


def test_a_plateau_stops_a_run_only_in_the_second_half_of_its_schedule(tiny_scene):
    trainer = Trainer(make_method(tiny_scene, _config(steps=1000)), log=lambda line: None)
    trainer.evals_since_best = trainer.preset.patience
    trainer.summary.steps = 400  # the rate has not fallen far yet: keep going
    assert not trainer.plateaued()
    trainer.summary.steps = 500
    assert trainer.plateaued()
    trainer.evals_since_best -= 1  # still rising within the patience
    assert not trainer.plateaued()


def test_sigterm_saves_the_step_it_was_at_and_the_fit_resumes_there(tiny_scene, tmp_path):
    import os
    import signal

    from seenerf.errors import TrainingStopped
    from seenerf.train.checkpoint import _read

    def terminate_at_step_3(trainer):
        if trainer.summary.steps == 3:
            os.kill(os.getpid(), signal.SIGTERM)

    trainer = Trainer(
        make_method(tiny_scene, _config(steps=50)),
        tmp_path,
        lambda line: None,
        0.0,
        terminate_at_step_3,
    )
    with pytest.raises(
        TrainingStopped, match="stopped at step 3 .SIGTERM.; checkpoint saved"
    ) as stop:
        trainer.train()
    assert stop.value.exit_status == 128 + signal.SIGTERM  # 143, as if the signal had ended it
    assert _read(tmp_path / "checkpoint.pt")["steps"] == 3
    assert signal.getsignal(signal.SIGTERM) is not None  # the handler is given back
    lines = []
    resumed = Trainer(make_method(tiny_scene, _config(steps=5)), tmp_path, lines.append)
    assert resumed.train().steps == 5 and any("resuming at step 3" in line for line in lines)


def test_progress_line_reports_losses_psnr_rate_and_eta(tiny_scene):
    lines = []
    trainer = Trainer(make_method(tiny_scene, _config(steps=4)), log=lines.append)
    trainer.preset = type(trainer.preset)(**{**trainer.preset.__dict__, "eval_every": 2})
    trainer.train()
    assert len(lines) == 2
    for part in ("step 2/4", "ldr", "events", "val PSNR", "steps/s", "ETA"):
        assert part in lines[0]
    assert math.isfinite(trainer.summary.history[-1]["val_psnr"])


def test_oracle_bounds_follow_the_truth_frame_not_the_estimated_one():
    from seenerf.train.methods import RecordingMethod, SharpTruthMethod

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    estimated = scene.c2w.copy()
    estimated[..., :3, 3] *= 10.0  # the reconstruction's frame: ten times the truth's scale
    scene.c2w, scene.bounds = estimated, scene.bounds * 10.0
    poses, bounds = SharpTruthMethod.training_frame(
        scene, _config(variant="oracle"), VARIANTS["oracle"]
    )
    np.testing.assert_allclose(bounds, [1.0, 3.0], rtol=1e-4)  # plane_scene's true bounds
    assert poses is scene.truth.c2w
    _, estimated_bounds = RecordingMethod.training_frame(scene, _config(), VARIANTS["full"])
    np.testing.assert_allclose(estimated_bounds, [10.0, 30.0])


def test_oracle_ldr_views_use_the_true_response():
    from seenerf.data.synthetic import true_response

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    model = make_method(scene, _config(variant="oracle")).model
    log_radiance = torch.tensor([[-4.0, -2.0, 1.5]])
    expected = true_response(np.array([-4.0, -2.0, 1.5]) + np.log(0.064))
    np.testing.assert_allclose(
        model.ldr_from_log(log_radiance, 0.064)[0].numpy(), expected, atol=2e-3
    )


def test_whole_image_ldr_matches_the_response_per_pixel():
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=0)
    model = make_method(scene, _config()).model
    with torch.no_grad():
        model.crf.weight_in.mul_(4.0)  # kinks steeper than the warm start's
    log_radiance = torch.linspace(-12.0, 6.0, 6000).reshape(2000, 3)
    exposures = (0.001, 0.016, 0.256)
    with torch.no_grad():
        tabulated = model.ldr_images(log_radiance, exposures)
        for image, exposure in zip(tabulated, exposures, strict=True):
            direct = model.ldr_from_log(log_radiance, exposure)
            assert (image - direct).abs().max() < 1e-3


def test_a_full_disk_keeps_the_previous_checkpoint(tiny_scene, tmp_path, monkeypatch):
    from seenerf.train.checkpoint import save_checkpoint

    trainer = Trainer(make_method(tiny_scene, _config(steps=2)), tmp_path, log=lambda line: None)
    trainer.train()
    before = (tmp_path / "checkpoint.pt").read_bytes()

    def disk_full(state, path):
        path.write_bytes(b"half")  # torch had begun the file
        raise RuntimeError("PytorchStreamWriter failed writing file data/0: file write failed")

    monkeypatch.setattr(torch, "save", disk_full)
    with pytest.raises(CheckpointError, match="previous checkpoint is kept.*to resume"):
        save_checkpoint(tmp_path / "checkpoint.pt", trainer)
    assert (tmp_path / "checkpoint.pt").read_bytes() == before
    assert not (tmp_path / "checkpoint.tmp").exists()
    monkeypatch.undo()
    resumed = Trainer(make_method(tiny_scene, _config(steps=3)), tmp_path, log=lambda line: None)
    assert resumed.train().steps == 3  # resumed from step 2, one more step


def test_the_budget_keeps_room_for_the_renders_and_scores_after_training(tiny_scene):
    from seenerf.train.trainer import OUTPUT_FIXED_S, OUTPUT_RENDERS_PER_VIEW

    lines = []
    trainer = Trainer(
        make_method(tiny_scene, _config(steps=None, time_budget_s=100.0, validation_share=0.2)),
        log=lines.append,
        spent_s=60.0,
    )
    assert trainer._training_budget() == 40.0  # nothing kept before the first validation
    height, width = tiny_scene.image_size
    rays = len(trainer.method.validation) * (tiny_scene.num_bins + 1)
    trainer._estimate_outputs(validation_s=0.5)
    # A view's rays at the validation's speed, six renders' worth per held-out view.
    per_view = height * width * 0.5 / rays
    views = len(tiny_scene.test.c2w)
    expected = views * OUTPUT_RENDERS_PER_VIEW * per_view + OUTPUT_FIXED_S
    assert trainer.outputs_s == pytest.approx(expected)
    assert trainer._training_budget() == pytest.approx(40.0 - expected)
    assert any("for the final renders and scores" in line for line in lines)
