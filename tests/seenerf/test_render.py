import math

import pytest
import torch

from seenerf.fields import PaperField, VectorMatrixField, positional_encoding, sample_vector_matrix
from seenerf.render.rays import SceneBox, camera_rays, intersect_box
from seenerf.render.sampling import OccupancyGrid, importance_samples, stratified_samples
from seenerf.render.volume import composite, sample_weights


def test_weights_and_composite_by_hand():
    # ray 0: two samples with optical depth ln 2 -> alpha 1/2 each -> weights 1/2, 1/4.
    # ray 1: no samples -> opacity 0 -> background only.
    density = torch.tensor([math.log(2), math.log(2)])
    delta = torch.ones(2)
    index = torch.tensor([0, 0])
    weights, opacity = sample_weights(density, delta, index, 2)
    assert weights.tolist() == pytest.approx([0.5, 0.25])
    assert opacity.tolist() == pytest.approx([0.75, 0.0])
    values = torch.tensor([[1.0], [2.0]])
    out = composite(weights, values, index, opacity, torch.tensor([8.0]))
    # 0.5 * 1 + 0.25 * 2 + 0.25 * 8 = 3; empty ray = background 8
    assert out[:, 0].tolist() == pytest.approx([3.0, 8.0])


def test_transmittance_restarts_for_every_ray_in_a_long_packed_batch():
    rays = 3000
    density = torch.full((rays * 4,), 50.0)  # each sample opaque
    index = torch.arange(rays).repeat_interleave(4)
    weights, opacity = sample_weights(density, torch.ones_like(density), index, rays)
    assert torch.allclose(weights.reshape(rays, 4)[:, 0], torch.ones(rays))
    assert torch.allclose(opacity, torch.ones(rays))


def test_equal_count_weights_match_the_ragged_packing():
    # The per-row cumulative sum (per_ray > 0) must give the ragged float64 path's weights.
    generator = torch.Generator().manual_seed(3)
    rays, per_ray = 500, 24
    density = torch.rand(rays * per_ray, generator=generator) * 20.0
    delta = torch.rand(rays * per_ray, generator=generator) * 0.1
    index = torch.arange(rays).repeat_interleave(per_ray)
    ragged, ragged_opacity = sample_weights(density, delta, index, rays)
    dense, dense_opacity = sample_weights(density, delta, index, rays, per_ray)
    assert torch.allclose(dense, ragged, atol=1e-6)
    assert torch.allclose(dense_opacity, ragged_opacity, atol=1e-6)
    # first sample of each ray: T = 1, so its weight is 1 - exp(-sigma delta)
    first = 1.0 - torch.exp(-(density * delta).reshape(rays, per_ray)[:, 0])
    assert torch.allclose(dense.reshape(rays, per_ray)[:, 0], first, atol=1e-7)


def test_equal_count_weights_of_no_rays_are_empty():
    weights, opacity = sample_weights(
        torch.zeros(0), torch.zeros(0), torch.zeros(0, dtype=torch.long), 0, 8
    )
    assert len(weights) == 0 and len(opacity) == 0


def test_ray_missing_the_box_gets_an_empty_interval():
    box = SceneBox((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    origins = torch.tensor([[0.0, 0.0, -3.0], [0.0, 5.0, -3.0]])
    directions = torch.tensor([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    entry, exit_ = intersect_box(origins, directions, box, 0.1, 100.0)
    assert entry.tolist() == pytest.approx([2.0, entry[1].item()])
    assert exit_[0].item() == pytest.approx(4.0)
    assert exit_[1].item() == entry[1].item()


def test_camera_rays_opencv_axes():
    # principal point (2, 1), focal 2: pixel (4, 1) looks along +x by 1 per unit depth.
    pose = torch.eye(4)
    pose[:3, 3] = torch.tensor([1.0, 2.0, 3.0])
    origins, directions = camera_rays(
        pose, torch.tensor([2.0, 2.0, 2.0, 1.0]), torch.tensor([4.0]), torch.tensor([1.0])
    )
    assert directions[0].tolist() == pytest.approx([1.0, 0.0, 1.0])
    assert origins[0].tolist() == pytest.approx([1.0, 2.0, 3.0])


def test_stratified_and_importance_samples():
    t, delta = stratified_samples(torch.tensor([1.0]), torch.tensor([3.0]), 4, None)
    assert t[0].tolist() == pytest.approx([1.25, 1.75, 2.25, 2.75])
    assert delta[0].tolist() == pytest.approx([0.5] * 4)
    weights = torch.tensor([[0.0, 0.0, 1.0, 0.0]])
    fine, fine_delta = importance_samples(
        t, delta, weights, 16, torch.Generator().manual_seed(0), merge=False
    )
    inside = ((fine >= 2.0) & (fine <= 2.5)).float().mean()
    assert inside > 0.9 and (fine_delta >= 0).all()


def test_occupancy_grid_skips_empty_cells_and_outside_points():
    grid = OccupancyGrid(resolution=4)
    grid.update(lambda p: (p[:, 0] > 0.5).float() * 100.0)
    assert grid.occupied.float().mean().item() == pytest.approx(0.25)
    points = torch.tensor([[0.9, 0.0, 0.0], [-0.9, 0.0, 0.0], [1.5, 0.0, 0.0]])
    assert grid.lookup(points).tolist() == [True, False, False]


def test_vector_matrix_sampling_by_hand():
    planes = torch.ones(3, 2, 8, 8)
    lines = torch.full((3, 2, 8, 1), 2.0)
    features = sample_vector_matrix(planes, lines, torch.rand(5, 3) * 2 - 1)
    assert torch.allclose(features, torch.full((5, 2), 6.0))  # 3 pairs x (1 x 2)


@pytest.mark.parametrize("channels", [8, 6])
def test_vector_matrix_lookups_in_channel_groups_match_one_lookup_per_plane(channels):
    import torch.nn.functional as F  # noqa: N812

    from seenerf.fields.factorised import _lookup

    generator = torch.Generator().manual_seed(3)
    features = torch.randn(3, channels, 7, 5, generator=generator, requires_grad=True)
    uv = torch.rand(3, 11, 2, generator=generator) * 2 - 1
    weights = torch.randn(3, channels, 11, generator=generator)
    (_lookup(features, uv) * weights).sum().backward()
    grouped_gradient = features.grad.clone()
    features.grad = None
    plain = F.grid_sample(features, uv[:, None], align_corners=True)[:, :, 0]
    assert torch.allclose(_lookup(features, uv), plain, atol=1e-6)
    (plain * weights).sum().backward()
    assert torch.allclose(grouped_gradient, features.grad, atol=1e-5)
    assert grouped_gradient.abs().sum() > 0


def test_smoothness_by_hand_and_its_written_out_gradient():
    from seenerf.fields.factorised import _SquaredSteps

    line = torch.tensor([[[0.0], [1.0], [3.0]]])  # steps 1 and 2 along the line
    assert _SquaredSteps.apply(line).item() == pytest.approx(2.5)
    plane = torch.tensor([[[0.0, 2.0], [1.0, 1.0]]])  # rows: 1, -1; columns: 2, 0
    assert _SquaredSteps.apply(plane).item() == pytest.approx(1.0 + 2.0)
    factor = torch.randn(2, 3, 5, 4, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(_SquaredSteps.apply, (factor,))


def test_positional_encoding_dimensions():
    assert positional_encoding(torch.zeros(2, 3), 10).shape == (2, 63)
    assert positional_encoding(torch.zeros(2, 3), 4).shape == (2, 27)


@pytest.mark.parametrize("field", [PaperField(), VectorMatrixField(resolution=16)])
def test_fields_give_finite_density_log_radiance_and_gradients(field):
    points = (torch.rand(64, 3) * 2 - 1).requires_grad_()
    directions = torch.nn.functional.normalize(torch.randn(64, 3), dim=-1)
    density, log_radiance = field(points, directions)
    assert density.shape == (64,) and log_radiance.shape == (64, 3)
    assert (density >= 0).all() and density.dtype == torch.float32
    (density.sum() + log_radiance.sum()).backward()
    assert all(torch.isfinite(p.grad).all() for p in field.parameters() if p.grad is not None)
    assert torch.allclose(field.density(points), density)
