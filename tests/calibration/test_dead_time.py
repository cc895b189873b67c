"""A pixel's dead time is found where the intervals between its events pile up."""

import numpy as np
import pytest

from davis_io.calibration.dead_time import dead_time_us
from davis_io.emulator.dvs import DvsParams, DvsPixels


def _stream(times_by_pixel: dict[tuple[int, int], np.ndarray], width: int):
    """Events of several ``(x, y)`` pixels merged in time order, as a camera sends them.

    Returns:
        Times and pixels ``y * width + x``.
    """
    times = np.concatenate(list(times_by_pixel.values()))
    pixel = np.concatenate([np.full(len(t), y * width + x) for (x, y), t in times_by_pixel.items()])
    order = np.argsort(times, kind="stable")
    return times[order], pixel[order]


def test_a_rate_limited_burst_sets_the_dead_time():
    # Pixel (3, 1) fires 300 times back to back every 1200 µs (a bright edge it cannot keep up
    # with); pixel (0, 2) fires 100 times 5-50 ms apart: 299 of the 398 intervals are 1200 µs,
    # the others longer, so the 1st percentile is 1200.
    rng = np.random.default_rng(0)
    times, pixel = _stream(
        {
            (3, 1): 1000 + 1200 * np.arange(300),
            (0, 2): np.cumsum(rng.integers(5000, 50000, 100)),
        },
        width=4,
    )
    assert dead_time_us(times, pixel) == 1200


def test_without_a_refractory_period_the_intervals_reach_down_to_zero():
    # 10,001 events of one pixel with intervals uniform in 0-10,000 µs: 1st percentile ~100 µs.
    rng = np.random.default_rng(1)
    times = np.cumsum(rng.integers(0, 10_001, 10_001))
    assert dead_time_us(times, np.zeros(len(times), int)) == pytest.approx(100, abs=30)


def test_no_pixel_firing_twice_has_no_dead_time():
    times, pixel = _stream({(0, 0): np.array([5]), (1, 0): np.array([7])}, width=2)
    assert dead_time_us(times, pixel) == 0


@pytest.mark.parametrize(("refractory_us", "low", "high"), [(1500, 1500, 1700), (0, 0, 100)])
def test_the_emulated_pixels_refractory_period_is_measured(refractory_us, low, high):
    # 16 pixels swept up and down by 5 thresholds per 1 ms step: they owe events faster than a
    # 1.5 ms refractory period lets them fire (within one sub-step of 200 µs of it); without one
    # they fire 5 per step, 200 µs apart.
    pixels = DvsPixels(DvsParams(threshold_sigma=0.0, refractory_us=refractory_us), 4, 4, seed=0)
    offsets = 0.05 * np.arange(16).reshape(4, 4)
    events = []
    for step in range(300):
        log_intensity = 10 - abs(step % 40 - 20) + offsets
        events.append(pixels.step(np.exp(log_intensity) / 255, 1000 * step))
    events = np.concatenate(events)
    pixel = events["y"].astype(int) * 4 + events["x"]
    assert low <= dead_time_us(events["t"], pixel) <= high
