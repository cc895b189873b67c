"""Our SSIM against scikit-image's, with the reference settings of Wang et al. (2004)."""

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from davis_io.aedat import open_recording
from seenerf.eval.metrics import ssim


@pytest.fixture
def real_frames(aestream_aedat4):
    with open_recording(aestream_aedat4) as recording:
        frames = [f.image for packet in recording for f in packet.frames]
    return [np.asarray(f, np.float64) / 255.0 for f in frames]


def _reference(a, b):
    # Gaussian window sigma 1.5 (11 x 11), population covariances, K1 0.01, K2 0.03, range 1.
    return structural_similarity(
        a, b, gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0
    )


def test_ssim_of_real_frames_matches_scikit_image(real_frames):
    first, second, third = real_frames
    rng = np.random.default_rng(3)
    noisy = np.clip(first + rng.normal(0, 0.05, first.shape), 0, 1)
    pairs = [(first, second), (first, third), (first, noisy), (first, first**1.5)]
    ours = [ssim(a, b) for a, b in pairs]
    theirs = [_reference(a, b) for a, b in pairs]
    # Both average over the window positions that fit inside the image: the same numbers.
    assert ours == pytest.approx(theirs, abs=1e-4)
    assert min(ours) < 0.9  # the pairs differ: not a comparison of constants
    assert ssim(first, first) == pytest.approx(1.0)
