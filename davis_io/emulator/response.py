"""Camera response curves: LDR value in [0, 1] from exposure-normalised radiance.

The curves take ``x = gain * radiance * exposure_s``; the emulator sets ``gain = 1 /
training_exposure_s`` so that at the training exposure ``x`` equals the radiance in scene units
(radiance 1 maps to ``reinhard_gamma(1) = 0.5 ** (1 / 2.2) = 0.73``, mid-grey 0.18 to 0.46).

* ``reinhard_gamma``: ``(x / (x + 1)) ** (1 / 2.2)``, the tone curve of See-NeRF's synthetic data.
* ``film``: a sigmoid of ``ln x`` with a soft toe and shoulder, like a film or camera ISP curve:
  ``1 / (1 + exp(-(ln x - ln 0.35) / 1.1))``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from davis_io.errors import UsageError

__all__ = ["RESPONSE_CURVES", "apply_response", "film", "reinhard_gamma", "response_table"]

_FILM_MIDPOINT = 0.35
_FILM_WIDTH = 1.1


def reinhard_gamma(x: np.ndarray) -> np.ndarray:
    """``(x / (x + 1)) ** (1 / 2.2)`` for ``x >= 0`` (negative inputs give 0)."""
    x = np.maximum(np.asarray(x, np.float64), 0)
    return (x / (x + 1)) ** (1 / 2.2)


def film(x: np.ndarray) -> np.ndarray:
    """Sigmoid of ``ln x``: 0.5 at ``x = 0.35``, slope set by a width of 1.1 in ``ln x``."""
    x = np.maximum(np.asarray(x, np.float64), 1e-300)
    return 1 / (1 + np.exp(-(np.log(x) - np.log(_FILM_MIDPOINT)) / _FILM_WIDTH))


RESPONSE_CURVES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "reinhard_gamma": reinhard_gamma,
    "film": film,
}
"""Response curves by name."""


def apply_response(name: str, x: np.ndarray) -> np.ndarray:
    """Apply the response curve called ``name`` to exposure-normalised radiance ``x`` (float64).

    Raises:
        UsageError: no curve has that name.
    """
    if name not in RESPONSE_CURVES:
        raise UsageError(
            f"unknown response curve {name!r}; choose one of {', '.join(RESPONSE_CURVES)}"
        )
    return RESPONSE_CURVES[name](x)


def response_table(
    name: str, gain: float, *, samples: int = 256, span: tuple[float, float] = (-12.0, 8.0)
) -> tuple[np.ndarray, np.ndarray]:
    """The curve tabulated against ``ln(radiance * exposure_s)``.

    Args:
        name: curve name.
        gain: the sensor gain (1 / training exposure in s) that multiplies radiance * exposure.
        samples: number of table entries.
        span: range of ``ln(gain * radiance * exposure_s)`` covered.

    Returns:
        ``log_exposure`` ``(K,)`` float64 ln(radiance * exposure_s) and ``value`` ``(K,)``
        float64 in [0, 1].
    """
    log_x = np.linspace(span[0], span[1], samples)
    return log_x - np.log(gain), apply_response(name, np.exp(log_x))
