import numpy as np
import pytest

from davis_io.errors import UsageError
from davis_io.poses.edi import MAX_LOG_CHANGE, cumulative_counts, edi_latent_frames


def psnr(a, b):
    return 10 * np.log10(1.0 / np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))


def test_hand_computed_single_pixel():
    # b = 2, one event per bin, theta = ln 2: C = (0, 1, 2), gains (1, 2, 4);
    # weights (1/4, 1/2, 1/4): denominator 0.25 + 1 + 1 = 2.25, so L_0 = 0.9 / 2.25 = 0.4.
    counts = np.ones((2, 1, 1))
    latent = edi_latent_frames(np.full((1, 1), 0.9), counts, [0.25, 0.5, 0.25], np.log(2))
    assert np.allclose(latent[:, 0, 0], [0.4, 0.8, 1.6])
    assert np.tensordot([0.25, 0.5, 0.25], latent, axes=1)[0, 0] == pytest.approx(0.9)


def test_cumulative_counts_start_at_zero():
    counts = np.array([1, -2, 3.0]).reshape(3, 1, 1)
    assert np.allclose(cumulative_counts(counts)[:, 0, 0], [0, 1, -1, 2])
    assert cumulative_counts(np.zeros((0, 2, 2))).shape == (1, 2, 2)  # b = 0: just C_0


def test_no_events_gives_the_blurry_frame_and_b_zero_works():
    blurry = np.random.default_rng(0).random((4, 5))
    latent = edi_latent_frames(blurry, np.zeros((3, 4, 5)), [0.25, 0.25, 0.25, 0.25], 0.3)
    assert np.allclose(latent, blurry[None].repeat(4, axis=0))
    assert np.allclose(edi_latent_frames(blurry, np.zeros((0, 4, 5)), [1.0], 0.3)[0], blurry)


def test_black_pixels_and_event_storms_stay_finite():
    blurry = np.array([[0.0, 1.0, 0.5]])
    counts = np.array([[[1e6, -1e6, 3.0]], [[1e6, -1e6, 0.0]]])
    latent = edi_latent_frames(blurry, counts, [0.25, 0.5, 0.25], 0.3)
    assert np.all(np.isfinite(latent))
    assert np.all(latent[:, 0, 0] == 0)  # black stays black
    # C = (0, -1e6, -2e6) is clamped to -12: the ratio between latent frames is bounded.
    assert latent[2, 0, 1] / latent[0, 0, 1] == pytest.approx(np.exp(-MAX_LOG_CHANGE))


@pytest.mark.parametrize(
    "counts, weights, threshold",
    [
        (np.zeros((2, 3, 3)), [0.5, 0.5], 0.3),  # b + 1 = 3 weights needed
        (np.zeros((2, 3, 3)), [0.5, 0.5, 0.5], 0.3),  # do not sum to 1
        (np.zeros((2, 3, 3)), [-0.5, 1.0, 0.5], 0.3),  # negative
        (np.zeros((2, 3, 4)), [0.25, 0.5, 0.25], 0.3),  # event map of another size
        (np.zeros((2, 3, 3)), [0.25, 0.5, 0.25], 0.0),  # threshold
        (np.zeros((3, 3)), [0.25, 0.5, 0.25], 0.3),  # not (b, H, W)
    ],
)
def test_bad_input_is_a_usage_error(counts, weights, threshold):
    with pytest.raises(UsageError):
        edi_latent_frames(np.zeros((3, 3)), counts, weights, threshold)


def ideal_events(log_frames, threshold):
    """Signed counts per interval from thresholding log changes against a per-pixel memory."""
    base = log_frames[0].copy()
    counts = []
    for frame in log_frames[1:]:
        n = np.fix((frame - base) / threshold)
        base += n * threshold
        counts.append(n)
    return np.array(counts)


def moving_sequence(hard: bool, steps=17, size=64):
    """A texture sliding 12 px sideways; the hard case adds clipped highlights and dark areas."""
    rng = np.random.default_rng(3)
    x = np.arange(size + steps)
    texture = 0.5 + 0.3 * np.sin(x / 3.0)[None] * rng.uniform(0.5, 1, (size, 1))
    if hard:
        texture[:, 20:26] = 4.0  # a highlight far above full scale
        texture[:, 40:50] = 0.004  # near-black shadow
    shifts = np.linspace(0, 12, steps)
    return np.array(
        [np.stack([np.interp(np.arange(size) + s, x, row) for row in texture]) for s in shifts]
    )


@pytest.mark.parametrize("hard", [False, True])
def test_edi_recovers_the_mid_frame_better_than_the_blur(hard):
    sharp = moving_sequence(hard)  # (17, 64, 64) linear radiance
    steps = len(sharp) - 1
    trapezoid = np.full(steps + 1, 1.0 / steps)
    trapezoid[[0, -1]] /= 2
    blurry = np.clip(np.tensordot(trapezoid, sharp, axes=1), 0, 1)  # the sensor clips at 1
    threshold = 0.2
    fine = ideal_events(np.log(sharp), threshold)
    b = 4  # bins of 4 sub-steps each; latent points at sub-frames 0, 4, 8, 12, 16
    counts = fine.reshape(b, steps // b, *fine.shape[1:]).sum(axis=1)
    latent = edi_latent_frames(blurry, counts, [0.125, 0.25, 0.25, 0.25, 0.125], threshold)
    truth = np.clip(sharp[8], 0, 1)
    gain = psnr(latent[2], truth) - psnr(blurry, truth)
    # Quantised events leave up to one threshold (22 %) of error per pixel; a 6 dB gain means
    # the blur's edge error shrank to about half.
    print(f"PSNR gain {gain:.2f} dB")
    assert gain > 6.0
    assert np.all(np.isfinite(latent))
