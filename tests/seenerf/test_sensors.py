import math

import numpy as np
import pytest
import torch

from seenerf.errors import ConfigError
from seenerf.sensors.event_crf import (
    EventCrf,
    EventModelSpec,
    event_log_radiance,
    low_pass,
    predicted_counts,
    rate_limited,
    v2e_intensity_factor,
)
from seenerf.sensors.exposure import blur_log_radiance
from seenerf.sensors.rgb_crf import (
    LinearCrf,
    MonotoneCrf,
    PowerCrf,
    RgbCrf,
    TabulatedCrf,
    apply_power_crf,
    apply_rgb_crf,
    warm_start_target,
)


def _identity_crf_weights():
    # Hidden unit 0 passes relu(u); the output sums it: CRF(u) = sigmoid(relu(u)).
    weight_in = torch.zeros(3, 4)
    weight_in[:, 0] = 1.0
    weight_out = torch.zeros(3, 4)
    weight_out[:, 0] = 1.0
    return weight_in, torch.zeros(3, 4), weight_out, torch.zeros(3)


def test_known_crf_maps_known_radiance():
    # radiance e, exposure 1 s -> u = 1 -> sigmoid(1) = 0.7310586;
    # radiance 0.5 at 1 s -> u < 0 -> relu 0 -> 0.5.
    u = torch.log(torch.tensor([[math.e, 0.5, math.e**2]])) + math.log(1.0)
    out = apply_rgb_crf(u, *_identity_crf_weights())
    assert out[0].tolist() == pytest.approx([0.7310586, 0.5, 0.8807971], abs=1e-6)


def test_power_crf_hand_values():
    # (0.25)^0.5 = 0.5; 4^0.5 = 2 clipped to 1.
    out = apply_power_crf(torch.log(torch.tensor([0.25, 4.0])), torch.tensor(0.5))
    assert out.tolist() == pytest.approx([0.5, 1.0])
    assert PowerCrf().anchor_loss() == 0


def test_tabulated_crf_interpolates_each_channel_and_holds_its_ends():
    table_x = [-1.0, 0.0, 2.0]
    values = [[0.0, 0.1, 0.2], [0.5, 0.3, 0.4], [1.0, 0.9, 0.8]]
    crf = TabulatedCrf(table_x, values)
    u = torch.tensor([[-0.5, 1.0, 5.0], [-3.0, 0.0, 0.5]])
    # channel 0 at -0.5: halfway 0 -> 0.5; channel 1 at 1: halfway 0.3 -> 0.9; channel 2 at 5:
    # beyond the end, 0.8. Row 2: below the start 0.0; on a knot 0.3; channel 2 a quarter of
    # the way from 0.4 to 0.8.
    assert crf(u).tolist() == [pytest.approx([0.25, 0.6, 0.8]), pytest.approx([0.0, 0.3, 0.5])]
    assert crf.anchor_loss() == 0 and not list(crf.parameters())
    assert not crf.clips_hard  # each channel reaches its top only at the table's end


def test_a_tabulated_response_that_stays_at_its_top_clips_hard():
    flat_top = [[0.0, 0.1, 0.2], [0.9, 0.3, 0.4], [0.9, 0.9, 0.8]]  # channel 0 flat from x = 0
    assert TabulatedCrf([-1.0, 0.0, 2.0], flat_top).clips_hard


def test_linear_crf_hand_values_and_no_gradient_where_it_clips():
    crf = LinearCrf(0.05, 0.9, anchor_log_exposure=0.0, anchor_value=0.5)
    # x = 1 is the anchor: 0.5; x = 0.5: 0.05 + 0.45 / 2; x = 4: 0.05 + 1.8 clips at 0.9.
    u = torch.log(torch.tensor([[1.0, 0.5, 4.0]])).requires_grad_()
    out = crf(u)
    assert out[0].tolist() == pytest.approx([0.5, 0.275, 0.9])
    out.sum().backward()
    assert u.grad[0].tolist() == pytest.approx([0.45, 0.225, 0.0])  # d/d ln x = 0.45 x
    assert crf.anchor_loss() == 0 and not list(crf.parameters()) and crf.clips_hard
    with pytest.raises(ConfigError, match="--response learned"):
        LinearCrf(0.6, 0.9)


def test_rgb_crf_warm_start_reaches_reference_curve():
    crf = RgbCrf(seed=3)
    crf.warm_start(steps=500)
    x = torch.linspace(-3, 3, 61)[:, None].expand(-1, 3)
    error = (crf(x) - warm_start_target(x)).abs().max()
    assert error < 0.08


def test_the_learned_response_rises_for_weights_that_would_fold_it_over():
    # Unit 0 rises as relu(u); unit 1 falls as relu(u - 2) with weight -3 out (free MLP):
    # relu(u) - 3 relu(u - 2) falls past u = 2, from sigmoid(2) at 2 to sigmoid(-2) at 4.
    weight_in = torch.zeros(3, 2)
    weight_in[:, 0] = weight_in[:, 1] = 1.0
    bias_in = torch.zeros(3, 2)
    bias_in[:, 1] = -2.0
    weight_out = torch.zeros(3, 2)
    weight_out[:, 0], weight_out[:, 1] = 1.0, -3.0
    u = torch.tensor([2.0, 4.0])[:, None].expand(-1, 3)
    folded = apply_rgb_crf(u, weight_in, bias_in, weight_out, torch.zeros(3))
    assert folded[:, 0].tolist() == pytest.approx([0.8807971, 0.1192029], abs=1e-6)
    crf = RgbCrf(hidden=2)
    with torch.no_grad():
        for parameter, value in zip(
            (crf.weight_in, crf.bias_in, crf.weight_out, crf.bias_out),
            (weight_in, bias_in, weight_out, torch.zeros(3)),
            strict=True,
        ):
            parameter.copy_(value)
    # Held rising, unit 1 adds 3 relu(u - 2): sigmoid(2) at 2, sigmoid(4 + 6) at 4.
    assert crf(u)[:, 0].tolist() == pytest.approx([0.8807971, 0.9999546], abs=1e-6)
    with torch.no_grad():
        for parameter in crf.parameters():
            parameter.normal_(generator=torch.Generator().manual_seed(5))
    dense = torch.linspace(-20, 20, 2001)[:, None].expand(-1, 3)
    values = crf(dense).detach()
    assert (values[1:] - values[:-1] >= -1e-6).all()


def test_the_monotone_response_follows_its_two_slopes_and_always_rises():
    crf = MonotoneCrf(anchor_log_exposure=0.0, anchor_value=0.5)
    x = torch.tensor([-20.0, -3.0, 0.0, 3.0, 20.0])[:, None].expand(-1, 3)
    start = torch.sigmoid(x)
    assert torch.allclose(crf(x), start)  # slope 1 at both knots: sigmoid(x - anchor)
    assert float(crf.anchor_loss().detach()) == 0.0
    with torch.no_grad():
        crf.raw_slopes[:, 1] = math.log(math.e**3 - 1.0)  # slopes 1 at -9 and 3 at +9
    # By hand: the slope is 1 + (u + 9) / 9 between the knots, so h(9) = 9 + 13.5 = 22.5,
    # h(-9) = -(9 + 4.5) = -13.5, and beyond the upper knot it rises by 3 per unit.
    at = torch.tensor([-10.0, -9.0, 0.0, 9.0, 10.0])[:, None].expand(-1, 3)
    expected = torch.sigmoid(torch.tensor([-14.5, -13.5, 0.0, 22.5, 25.5]))
    assert torch.allclose(crf(at)[:, 0].double().logit(), expected.double().logit(), atol=1e-3)
    with torch.no_grad():
        crf.raw_slopes.copy_(torch.tensor([[-30.0, 4.0], [2.0, -30.0], [0.0, 0.0]]))
    dense = torch.linspace(-40, 40, 4001, dtype=torch.float64)[:, None].expand(-1, 3)
    values = crf.double()(dense)
    # Rising for any slopes, even nearly flat ones (to rounding, where the curve is flat).
    assert (values[1:] - values[:-1] >= -1e-12).all()
    assert (values[-1] - values[0] > 0.5).all()


def test_anchor_loss_is_zero_for_a_curve_through_the_anchor():
    crf = RgbCrf(anchor_log_exposure=0.0, anchor_value=0.5)
    with torch.no_grad():
        for p in crf.parameters():
            p.zero_()  # sigmoid(0) = 0.5 everywhere
    assert float(crf.anchor_loss().detach()) == 0.0
    crf.anchor_value = 0.6
    assert float(crf.anchor_loss().detach()) == pytest.approx(0.01, abs=1e-7)


def test_trapezoid_exposure_integral():
    # b = 2: weights 1/4, 1/2, 1/4 of radiance 1, 2, 4 -> 0.25 + 1 + 1 = 2.25.
    log_e = torch.log(torch.tensor([[1.0, 2.0, 4.0]]))[..., None].expand(-1, -1, 3)
    out = blur_log_radiance(log_e, torch.tensor([[0.25, 0.5, 0.25]]))
    assert torch.allclose(out, torch.full((1, 3), math.log(2.25)))


def test_exposure_integral_extreme_values_and_zero_weight_are_finite():
    log_e = torch.tensor([[[-80.0] * 3, [80.0] * 3, [0.0] * 3]], requires_grad=True)
    out = blur_log_radiance(log_e, torch.tensor([[0.0, 0.5, 0.5]]))
    out.sum().backward()
    assert torch.isfinite(out).all() and torch.isfinite(log_e.grad).all()
    assert out[0, 0].item() == pytest.approx(80 + math.log(0.5), rel=1e-6)


def test_low_pass_first_and_second_order_by_hand():
    signal = torch.tensor([[0.0, 1.0, 1.0]])
    eps = torch.tensor([[0.0, 0.5, 0.5]])
    # s1 = 0.5 * 0 + 0.5 * 1 = 0.5; s2 = 0.5 * 0.5 + 0.5 * 1 = 0.75
    assert low_pass(signal, eps, 1)[0].tolist() == pytest.approx([0.0, 0.5, 0.75])
    # second stage on [0, 0.5, 0.75]: 0.25, then 0.5 * 0.25 + 0.5 * 0.75 = 0.5
    assert low_pass(signal, eps, 2)[0].tolist() == pytest.approx([0.0, 0.25, 0.5])
    assert low_pass(signal, eps, 0) is signal
    # eps is clamped to [0, 1]: eps 3 behaves as 1 (no delay)
    assert low_pass(signal, eps * 6, 1)[0].tolist() == pytest.approx([0.0, 1.0, 1.0])


def test_predicted_counts_from_known_sequence():
    # (0.5 - 0) / 0.3 = 1.6667, (0.75 - 0.5) / 0.3 = 0.8333
    counts = predicted_counts(torch.tensor([[0.0, 0.5, 0.75]]), 0.3)
    assert counts[0].tolist() == pytest.approx([5 / 3, 5 / 6])


def test_rate_limited_pixels_fire_their_cap_and_owe_the_rest_by_hand():
    # Cap 3 ON, 2 OFF per bin. Owed 5 -> fire 3, owe 2; +5 -> 7: fire 3, owe 4; +0: fire 3, owe
    # 1; -3 -> -2: fire -2, owe 0. A pixel under its cap fires what it is asked.
    counts = torch.tensor([[5.0, 5.0, 0.0, -3.0], [1.0, -1.5, 2.0, 0.0]], requires_grad=True)
    fired = rate_limited(counts, torch.tensor(3.0), torch.tensor(2.0))
    assert fired.tolist() == [[3.0, 3.0, 3.0, -2.0], [1.0, -1.5, 2.0, 0.0]]
    # What was owed at the end (a count still owed after the last bin) is not fired.
    three = torch.tensor(3.0)
    assert rate_limited(torch.tensor([[9.0, 0.0]]), three, three).tolist() == [[3.0, 3.0]]
    # A bin under its cap fires what it is asked and what is owed: 5 -> 3 (owe 2), 0.5 -> 2.5;
    # its count depends on the earlier request, a capped bin's on no request.
    asked = torch.tensor([[5.0, 0.5, 0.0]], requires_grad=True)
    fired = rate_limited(asked, three, three)
    assert fired.tolist() == [[3.0, 2.5, 0.0]]
    fired[0, 1].backward()
    assert asked.grad.tolist() == [[1.0, 1.0, 0.0]]
    asked.grad = None
    fired = rate_limited(asked, three, three)
    fired[0, 0].backward()
    assert asked.grad.tolist() == [[0.0, 0.0, 0.0]]


def test_event_crf_with_a_dead_time_caps_each_bin_by_polarity():
    # No delay; exposure 4 ms, b = 2 -> 2 ms bins; dead time 1 ms -> 2 events per bin, in units
    # of the mean threshold 0.3: ON threshold 0.45 (scale 1.5) -> cap 3, OFF 0.15 -> cap 1.
    spec = EventModelSpec(delay="none")
    crf = EventCrf(spec, threshold=0.3, dead_time_s=1e-3, polarity_scale=(1.5, 0.5))
    log_e = torch.tensor([[[0.0] * 3, [1.5] * 3, [1.5] * 3], [[0.0] * 3, [-0.6] * 3, [-0.6] * 3]])
    counts = crf(log_e, torch.tensor([[0.0, 1.0, 0.0]] * 2), torch.tensor([4e-3, 4e-3]))
    # asked 5, 0 -> fired 3, 2; asked -2, 0 -> fired -1, -1
    assert counts.tolist() == [pytest.approx([3.0, 2.0]), pytest.approx([-1.0, -1.0])]
    free = EventCrf(spec, threshold=0.3)(log_e, torch.tensor([[0.0, 1.0, 0.0]] * 2), torch.ones(2))
    assert free.tolist() == [pytest.approx([5.0, 0.0]), pytest.approx([-2.0, 0.0])]


def test_event_crf_follows_a_rate_limited_pixel_between_a_bins_ends():
    # Exposure 4 ms, b = 2, 2 sub-frames per bin -> 1 ms steps; dead time 1 ms -> 1 event per
    # step, threshold 0.5. The light rises 2 ln in the second step of bin 0 (4 events asked):
    # steps fire 0, 1, 1, 1 -> bins 1, 2 (one event still owed). Read at the bins' ends alone,
    # the rise is spread over bin 0 (cap 2): 2, 2.
    spec = EventModelSpec(delay="none")
    crf = EventCrf(spec, threshold=0.5, dead_time_s=1e-3)
    green = torch.tensor([[0.0, 1.0, 0.0]])
    rise = torch.tensor([0.0, 0.0, 2.0, 2.0, 2.0])[None, :, None].expand(1, 5, 3)
    exposure = torch.tensor([4e-3])
    assert crf(rise, green, exposure, subframes=2).tolist() == [pytest.approx([1.0, 2.0])]
    assert crf(rise[:, ::2], green, exposure).tolist() == [pytest.approx([2.0, 2.0])]
    # Without a dead time the steps of a bin add up to its ends' change.
    free = EventCrf(spec, threshold=0.5)
    wavy = torch.tensor([0.0, 1.0, -0.5, 0.25, 2.0])[None, :, None].expand(1, 5, 3)
    assert free(wavy, green, exposure, subframes=2).tolist() == [pytest.approx([-1.0, 5.0])]


def test_event_pixel_sees_its_bayer_channel_or_luminance():
    log_e = torch.log(torch.tensor([[[1.0, 2.0, 4.0]]]))
    red = event_log_radiance(log_e, torch.tensor([[1.0, 0.0, 0.0]]))
    assert red.item() == pytest.approx(0.0, abs=1e-6)
    luminance = event_log_radiance(log_e, torch.tensor([[0.2126, 0.7152, 0.0722]]))
    assert luminance.item() == pytest.approx(math.log(0.2126 + 2 * 0.7152 + 4 * 0.0722), rel=1e-6)


def test_v2e_intensity_factor_at_unit_exposure():
    # x = 1: (1 / 2)^(1 / 2.2) = 0.72974
    assert v2e_intensity_factor(torch.tensor(0.0)).item() == pytest.approx(
        0.5 ** (1 / 2.2), rel=1e-6
    )


def _constant_delay(crf: EventCrf, value: float) -> None:
    with torch.no_grad():
        for p in crf.delay.parameters():
            p.zero_()
        crf.delay[2].bias.fill_(math.log(value / (1 - value)))  # sigmoid(bias) = value


def test_event_crf_reference_reading_by_hand():
    # cutoff such that tau = 1 ms; exposure 4 ms, b = 2 -> bin 2 ms; f_ev = 0.25 -> eps = 0.5.
    crf = EventCrf(EventModelSpec(), threshold=0.3, cutoff_hz=1 / (2 * math.pi * 1e-3))
    _constant_delay(crf, 0.25)
    log_e = torch.tensor([[[0.0] * 3, [1.0] * 3, [1.0] * 3]])
    counts = crf(log_e, torch.tensor([[0.0, 1.0, 0.0]]), torch.tensor([4e-3]))
    assert counts[0].tolist() == pytest.approx([5 / 3, 5 / 6], rel=1e-5)


def test_event_crf_paper_reading_filters_linear_radiance():
    crf = EventCrf(EventModelSpec(order=2, domain="linear"), cutoff_hz=1 / (2 * math.pi * 1e-3))
    _constant_delay(crf, 0.25)
    log_e = torch.log(torch.tensor([[[1.0] * 3, [2.0] * 3, [2.0] * 3]]))
    counts = crf(log_e, torch.tensor([[0.0, 1.0, 0.0]]), torch.tensor([4e-3]))
    # radiance [1, 2, 2] -> stage 1 [1, 1.5, 1.75] -> stage 2 [1, 1.25, 1.5]
    expected = [math.log(1.25) / 0.3, math.log(1.5 / 1.25) / 0.3]
    assert counts[0].tolist() == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("bins", [1, 8])
def test_event_crf_large_and_tiny_values_stay_finite(bins):
    crf = EventCrf(EventModelSpec())
    log_e = torch.linspace(-70, 70, (bins + 1) * 3).reshape(1, bins + 1, 3).requires_grad_()
    counts = crf(log_e, torch.tensor([[0.2126, 0.7152, 0.0722]]), torch.tensor([0.256]))
    loss = (counts - 1e4).square().mean()
    loss.backward()
    assert counts.shape == (1, bins) and counts.dtype == torch.float32
    assert torch.isfinite(loss) and torch.isfinite(log_e.grad).all()


def test_learned_colour_mix_starts_as_channel_mean():
    crf = EventCrf(EventModelSpec(colour="learned", delay="none", order=0))
    log_e = torch.log(torch.tensor([[[3.0, 3.0, 3.0], [6.0, 6.0, 6.0]]]))
    counts = crf(log_e, torch.tensor([[1.0, 0.0, 0.0]]), torch.tensor([0.01]))
    assert counts.item() == pytest.approx(math.log(2) / 0.3, rel=1e-5)
    assert np.isfinite(counts.detach().numpy()).all()


def test_linear_levels_that_cannot_hold_the_anchor_fall_back_to_a_learned_response():
    from seenerf.data.synthetic import plane_scene
    from seenerf.model.config import FitConfig
    from seenerf.train.builder import rgb_response

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    scene.linear_levels = (-0.1, 1.0)  # a black level below zero: no linear response has it
    with pytest.warns(UserWarning, match="black level -0.100 .* the response is learned"):
        crf = rgb_response(RgbCrf, scene, FitConfig())
    assert isinstance(crf, RgbCrf)
    scene.linear_levels = (0.05, 0.9)
    assert isinstance(rgb_response(RgbCrf, scene, FitConfig()), LinearCrf)
