import numpy as np
import pytest

from davis_io import SeecapError
from davis_io.errors import DavisIOError
from davis_io.types import ColorFilter
from seenerf.data.arrays import pixel_layout
from seenerf.data.synthetic import plane_scene
from seenerf.errors import SeeNerfError, TrainingDataError


def test_rggb_layout_picks_one_channel_per_site():
    mix, channel = pixel_layout(ColorFilter.RGGB, 2, 4)
    assert channel.tolist() == [[0, 1, 0, 1], [1, 2, 1, 2]]
    assert mix[1, 1].tolist() == [0, 0, 1]


def test_mono_layout_is_luminance_through_the_first_curve():
    mix, channel = pixel_layout(ColorFilter.MONO, 2, 2)
    assert mix[0, 0].tolist() == pytest.approx([0.2126, 0.7152, 0.0722])
    assert (channel == 0).all()


def test_validate_names_the_bad_array():
    scene = plane_scene(height=6, width=8, frames=2, b=2, test_views=0)
    scene.weights = scene.weights[:, :2]
    with pytest.raises(TrainingDataError, match=r"weights has shape \(2, 2\), expected \(2, 3\)"):
        scene.validate()


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("ldr", 2.0, "divide by 1023"),
        ("exposure_s", 0.0, "> 0 seconds"),
    ],
)
def test_validate_ranges(field, value, message):
    scene = plane_scene(height=6, width=8, frames=2, b=2, test_views=0)
    getattr(scene, field)[0] = value
    with pytest.raises(TrainingDataError, match=message):
        scene.validate()


def test_errors_are_caught_by_the_cli():
    assert issubclass(SeeNerfError, SeecapError) and issubclass(DavisIOError, SeecapError)
    assert not issubclass(SeeNerfError, DavisIOError)


def test_synthetic_scene_ideal_events_match_the_latent_radiance():
    scene = plane_scene(height=6, width=8, frames=2, b=2, test_views=0)
    latent = scene.truth.sharp_hdr[:, ::4]
    log_pixel = np.log((latent * scene.mix).sum(-1))
    # bins are the log change of each pixel's own channel divided by 0.3
    assert np.allclose(scene.bins * 0.3, np.diff(log_pixel, axis=1), atol=1e-5)
    assert np.allclose(scene.weights.sum(1), 1.0)


@pytest.mark.parametrize("use_settled", [True, False])
def test_batches_carry_where_each_pixel_was_settled(use_settled):
    import dataclasses

    import torch

    from seenerf.data.batching import FrameSampler

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    settled = np.ones((3, 3, 8, 10), bool)
    settled[1, 2, 5, 7] = settled[2, 0, 0, 3] = False
    data = dataclasses.replace(scene, settled=settled).validate()
    sampler = FrameSampler(data, np.arange(3), dead_time=use_settled)
    batch = sampler.batch(torch.tensor([1, 2, 0]), torch.tensor([5 * 10 + 7, 3, 5 * 10 + 7]))
    expected = [[1, 1, 0], [0, 1, 1], [1, 1, 1]] if use_settled else np.ones((3, 3))
    assert batch.settled.tolist() == np.asarray(expected, bool).tolist()


def test_lone_frames_are_those_alone_in_their_stretch_of_the_stream():
    import dataclasses

    scene = plane_scene(height=8, width=10, frames=5, b=2, test_views=0)
    assert scene.lone_frames.tolist() == [False] * 5  # stretches not known
    lead = np.zeros((5, 8, 10), np.float32)
    data = dataclasses.replace(scene, lead=lead, stretch=np.array([0, 0, 4, 7, 7])).validate()
    assert data.lone_frames.tolist() == [False, False, True, False, False]


@pytest.mark.parametrize("lone_exposure_spans", [True, False])
def test_a_batch_marks_the_pixels_of_lone_frames(lone_exposure_spans):
    import dataclasses

    import torch

    from seenerf.data.batching import FrameSampler

    scene = plane_scene(height=8, width=10, frames=3, b=3, test_views=0)
    settled = np.ones((3, 4, 8, 10), bool)
    settled[2, 3, 2, 2] = False  # frame 2's last point: that pixel still owed events there
    data = dataclasses.replace(
        scene,
        lead=np.zeros((3, 8, 10), np.float32),
        stretch=np.array([0, 0, 1]),
        settled=settled,
    ).validate()
    sampler = FrameSampler(data, np.arange(3), lone_exposure_spans=lone_exposure_spans)
    batch = sampler.batch(torch.tensor([2, 1, 2]), torch.tensor([0, 2 * 10 + 2, 2 * 10 + 2]))
    assert batch.settled.tolist() == [[True] * 4, [True] * 4, [True, True, True, False]]
    assert batch.lone.tolist() == ([True, False, True] if lone_exposure_spans else [False] * 3)


def test_settled_points_must_match_the_bins():
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    scene.settled = np.ones((3, 2, 8, 10), bool)
    with pytest.raises(TrainingDataError, match=r"settled has shape \(3, 2, 8, 10\)"):
        scene.validate()


def test_spans_join_latent_points_of_one_stretch_and_carry_the_change_between():
    import dataclasses

    import torch

    from seenerf.data.batching import FrameSampler

    scene = plane_scene(height=8, width=10, frames=4, b=2, test_views=0)
    lead = np.zeros((4, 8, 10), np.float32)
    lead[1], lead[2] = 1.0, 5.0  # frame 3 starts a new stretch: its lead is 0 again
    scene.bins[:] = 0.5
    settled = np.ones((4, 3, 8, 10), bool)
    settled[1, 1] = False  # frame 1 mid-exposure: a pixel still owed events there
    data = dataclasses.replace(
        scene, lead=lead, stretch=np.array([0, 0, 0, 1]), settled=settled
    ).validate()
    sampler = FrameSampler(data, np.arange(4), event_share=0.0)
    spans = sampler.spans(2000, 2, torch.Generator().manual_seed(0))
    assert spans.origins.shape == (2000, 2, 3) and spans.directions.shape == (2000, 2, 3)
    centres = torch.as_tensor(data.c2w[:, :, :3, 3]).reshape(-1, 3)
    which = torch.cdist(spans.origins.reshape(-1, 3), centres).argmin(dim=1).reshape(-1, 2)
    frame, point = which // 3, which % 3
    level = torch.as_tensor(lead[:, 0, 0])[frame] + 0.5 * point
    expected = level[:, 1] - level[:, 0]
    torch.testing.assert_close(spans.change, expected.float())
    assert torch.equal(frame[:, 0] == 3, frame[:, 1] == 3)  # frame 3's stretch is its own
    unsettled = ((frame == 1) & (point == 1)).any(dim=1)
    assert torch.equal(spans.known, ~unsettled)
    assert (frame[:, 1] - frame[:, 0]).abs().max() == 2 and (frame[:, 0] == 3).any()


def test_span_loss_counts_known_spans_only_and_large_errors_linearly():
    import torch

    from seenerf.train.losses import span_loss

    predicted = torch.tensor([0.5, -3.0, 10.0])
    measured = torch.tensor([0.0, 0.0, 0.0])
    known = torch.tensor([True, True, False])
    # squared within one threshold, then linear: 2 * 3 - 1 for the second
    assert float(span_loss(predicted, measured, known)) == pytest.approx((0.25 + 5) / 2)
    assert float(span_loss(predicted, measured, torch.zeros(3, dtype=torch.bool))) == 0.0
    # weighed: the second span five times, the unknown third's weight changes nothing
    weights = torch.tensor([1.0, 5.0, 7.0])
    assert float(span_loss(predicted, measured, known, weights)) == pytest.approx((0.25 + 25) / 2)
