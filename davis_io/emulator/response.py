"""APS response curves: LDR value in [0, 1] from exposure-normalised radiance ``x``.

The curves take ``x = gain_per_s * radiance * exposure_s``; the emulator sets ``gain_per_s =
1 / training_exposure_s`` so that at the training exposure ``x`` equals the radiance in scene
units. Each :class:`Response` first multiplies ``x`` by its own ``gain``. Families:

* ``reinhard_gamma``: ``(g x / (g x + 1)) ** (1 / gamma)``, the tone curve of See-NeRF's
  synthetic data at ``g = 1``, ``gamma = 2.2`` (radiance 1 reads 0.73, mid-grey 0.18 reads 0.46).
* ``film``: a sigmoid of ``ln(g x)`` with a soft toe and shoulder, like a film or an ISP curve:
  ``1 / (1 + exp(-(ln(g x) - ln midpoint) / width))``.
* ``linear``: a raw DAVIS frame, ``min(black + slope * g x, saturation)``: linear in exposure
  above a black level, clipped where the pixel or its ADC saturates.
* ``s_curve``: a contrast S-curve on top of ``reinhard_gamma``: with ``s`` that curve's value,
  ``s ** c / (s ** c + (1 - s) ** c)``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from davis_io.errors import UsageError

__all__ = [
    "RESPONSE_CURVES",
    "RESPONSE_FAMILIES",
    "Response",
    "apply_response",
    "film",
    "reinhard_gamma",
    "response_table",
]

RESPONSE_FAMILIES = ("reinhard_gamma", "film", "linear", "s_curve")
"""Every response family the emulator knows."""


@dataclass(frozen=True)
class Response:
    """A response curve: a family and its parameters (those of other families are unused).

    Attributes:
        family: one of :data:`RESPONSE_FAMILIES`.
        gain: multiplies ``x`` before the curve.
        gamma: exponent of ``reinhard_gamma`` and ``s_curve``.
        midpoint: ``x`` where ``film`` reads 0.5.
        width: ``film``'s slope parameter in ``ln x``.
        contrast: ``s_curve``'s exponent ``c``.
        black: ``linear``'s value at ``x = 0`` (black level, fraction of full scale).
        slope: ``linear``'s value per unit ``x``.
        saturation: ``linear``'s largest value (fraction of full scale).
    """

    family: str = "reinhard_gamma"
    gain: float = 1.0
    gamma: float = 2.2
    midpoint: float = 0.35
    width: float = 1.1
    contrast: float = 1.0
    black: float = 0.0
    slope: float = 0.4
    saturation: float = 1.0

    def __post_init__(self) -> None:
        if self.family not in RESPONSE_FAMILIES:
            raise UsageError(
                f"unknown response curve {self.family!r}; choose one of "
                f"{', '.join(RESPONSE_FAMILIES)}"
            )
        if min(self.gain, self.gamma, self.midpoint, self.width, self.contrast, self.slope) <= 0:
            raise UsageError(f"response parameters must be positive: {self}")
        if not 0 <= self.black < self.saturation <= 1:
            raise UsageError(f"response needs 0 <= black < saturation <= 1: {self}")

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """The LDR value (float64 in [0, 1]) of exposure-normalised radiance ``x``."""
        x = self.gain * np.maximum(np.asarray(x, np.float64), 0)
        if self.family == "film":
            return 1 / (1 + (np.maximum(x, 1e-300) / self.midpoint) ** (-1 / self.width))
        if self.family == "linear":
            return np.minimum(self.black + self.slope * x, self.saturation)
        tone = (x / (x + 1)) ** (1 / self.gamma)
        if self.family == "s_curve":
            raised = tone**self.contrast
            return raised / (raised + (1 - tone) ** self.contrast)
        return tone

    def to_json(self) -> dict:
        """The family and the parameters it uses."""
        used = {
            "reinhard_gamma": ("gain", "gamma"),
            "film": ("gain", "midpoint", "width"),
            "linear": ("gain", "black", "slope", "saturation"),
            "s_curve": ("gain", "gamma", "contrast"),
        }[self.family]
        return {"family": self.family, **{name: getattr(self, name) for name in used}}

    @classmethod
    def from_json(cls, data: dict) -> Response:
        """Inverse of :meth:`to_json`."""
        names = {f.name for f in dataclasses.fields(cls)}
        return cls(**{key: value for key, value in data.items() if key in names})


def reinhard_gamma(x: np.ndarray) -> np.ndarray:
    """``(x / (x + 1)) ** (1 / 2.2)`` for ``x >= 0`` (negative inputs give 0)."""
    return Response("reinhard_gamma")(x)


def film(x: np.ndarray) -> np.ndarray:
    """Sigmoid of ``ln x``: 0.5 at ``x = 0.35``, slope set by a width of 1.1 in ``ln x``."""
    return Response("film")(x)


RESPONSE_CURVES: dict[str, Response] = {
    "reinhard_gamma": Response("reinhard_gamma"),
    "film": Response("film"),
    "linear": Response("linear", black=0.04, slope=0.3, saturation=0.95),
    "s_curve": Response("s_curve", contrast=1.6),
}
"""Named curves of the emulator's default sensors."""


def _resolve(response: str | Response) -> Response:
    if isinstance(response, Response):
        return response
    if response not in RESPONSE_CURVES:
        raise UsageError(
            f"unknown response curve {response!r}; choose one of {', '.join(RESPONSE_CURVES)}"
        )
    return RESPONSE_CURVES[response]


def apply_response(response: str | Response, x: np.ndarray) -> np.ndarray:
    """Apply a response (or the named curve) to exposure-normalised radiance ``x`` (float64).

    Raises:
        UsageError: no curve has that name.
    """
    return _resolve(response)(x)


def response_table(
    response: str | Response,
    gain: float,
    *,
    samples: int = 256,
    span: tuple[float, float] = (-12.0, 8.0),
) -> tuple[np.ndarray, np.ndarray]:
    """The curve tabulated against ``ln(radiance * exposure_s)``.

    Args:
        response: a response or a curve name.
        gain: the sensor gain (1 / training exposure in s) that multiplies radiance * exposure.
        samples: number of table entries.
        span: range of ``ln(gain * radiance * exposure_s)`` covered.

    Returns:
        ``log_exposure`` ``(K,)`` float64 ln(radiance * exposure_s) and ``value`` ``(K,)``
        float64 in [0, 1].
    """
    log_x = np.linspace(span[0], span[1], samples)
    return log_x - np.log(gain), apply_response(response, np.exp(log_x))
