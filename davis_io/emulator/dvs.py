"""The DVS pixel array, v2e-style: lin-log, intensity-dependent low-pass, mismatch, leak, noise.

Each call to :meth:`DvsPixels.step` advances every pixel from the previous sample time to the
next (times strictly increasing, integer µs) and returns the events of that step, sorted by time.
Per pixel (the model of v2e and See-NeRF's fork of it), with ``I = 255 * radiance`` the digital
intensity through its own colour filter:

1. lin-log ``L = I * ln(T) / T`` for ``I <= T``, else ``ln I`` (``T`` = ``linlog_threshold``);
2. low-pass ``lp <- (1 - eps) * lp + eps * L``, ``eps = min(1, f(I) * dt / tau)``,
   ``tau = 1 / (2 pi cutoff)``, ``f`` the intensity factor; with ``one_step_delay`` (the See-NeRF
   fork) events are computed from the previous step's ``lp``; cutoff 0 means ``lp = L``;
3. leak ``base -= dt * leak_rate * n * (1 - jitter * N(0, 1)) * theta_on`` with a per-pixel
   log-normal ``n = 10 ** (rate_cov_decades * N(0, 1))``;
4. counts ``floor(max(+-(lp - base), 0) / theta)`` with per-pixel thresholds
   ``theta ~ N(nominal, sigma)`` clamped at 0.01;
5. with ``M`` the largest count of the step, a pixel's ``n`` events fire at
   ``t_prev + ((i + 1) * dt_us) // M``, ``i < n``; when ``refractory_us`` exceeds the sub-step
   ``dt_us / M`` (as in v2e), an event within ``refractory_us`` of the pixel's previous event is
   dropped and its threshold stays in ``lp - base``;
6. shot noise: probability ``p = rate / 2 * dt * (1 - 0.75 * f(I))`` per step, ON when
   ``U > 1 - p * theta_nominal / theta``, OFF when ``U < p * theta_nominal / theta``, stamped at
   the step's end time; ``base`` resets to ``lp`` there. (The fork computes but drops these; here
   they are emitted, at the preset's rate.)

Events sharing a timestamp come in row-major pixel order (v2e shuffles them; nothing downstream
depends on the order within one microsecond). The low-pass is the v2e Euler step, so with steps
longer than ``tau / f`` it passes the input through (plus the one-step delay of the fork).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.errors import UsageError
from davis_io.types import EVENT_DTYPE

__all__ = ["DVS_PRESETS", "DvsParams", "DvsPixels", "intensity_factor", "lin_log"]

_MIN_THRESHOLD = 0.01


@dataclass(frozen=True)
class DvsParams:
    """Parameters of the pixel model (one preset of :data:`DVS_PRESETS` or your own).

    Attributes:
        threshold_on: nominal ON contrast threshold (log units).
        threshold_off: nominal OFF contrast threshold.
        threshold_sigma: standard deviation of the per-pixel thresholds.
        cutoff_hz: photoreceptor cutoff at full intensity factor; 0 disables the low-pass.
        leak_rate_hz: mean rate of leak (spontaneous ON) events per pixel.
        shot_noise_rate_hz: rate of shot-noise events per pixel at zero intensity factor.
        refractory_us: dead time after each event of a pixel, µs.
        leak_jitter: relative jitter of the leak per step.
        rate_cov_decades: spread of the per-pixel leak rate, decades.
        linlog_threshold: intensity ``T`` where the log response becomes linear (digital units).
        intensity_curve: ``"reinhard_gamma"`` (fork: ``(x/(x+1))**(1/2.2)``, ``x = I/255``) or
            ``"affine"`` (upstream v2e: ``(I + 20) / 275``).
        one_step_delay: events are computed from the previous step's low-pass state (fork).
    """

    threshold_on: float = 0.2
    threshold_off: float = 0.2
    threshold_sigma: float = 0.02
    cutoff_hz: float = 0.0
    leak_rate_hz: float = 0.0
    shot_noise_rate_hz: float = 0.0
    refractory_us: int = 0
    leak_jitter: float = 0.0
    rate_cov_decades: float = 0.0
    linlog_threshold: float = 1e-4
    intensity_curve: str = "reinhard_gamma"
    one_step_delay: bool = True


DVS_PRESETS: dict[str, DvsParams] = {
    "clean": DvsParams(),
    "noisy": DvsParams(0.3, 0.3, 0.03, 300.0, 0.01, 0.001, 500, 0.1, 0.01),
    "v2e-clean": DvsParams(linlog_threshold=20.0, intensity_curve="affine", one_step_delay=False),
    "v2e-noisy": DvsParams(0.2, 0.2, 0.05, 30.0, 0.1, 5.0, 0, 0.1, 0.1, 20.0, "affine", False),
}
"""``clean`` and ``noisy`` are the See-NeRF fork's presets; ``v2e-*`` are upstream v2e's."""


def lin_log(intensity: np.ndarray, threshold: float) -> np.ndarray:
    """Lin-log response (float32): linear through the origin below ``threshold``, log above."""
    intensity = np.asarray(intensity, np.float32)
    logarithm = np.log(np.maximum(intensity, np.float32(threshold)))
    linear = intensity * np.float32(np.log(threshold) / threshold)
    return np.where(intensity <= threshold, linear, logarithm)


def intensity_factor(intensity: np.ndarray, curve: str) -> np.ndarray:
    """Bandwidth and noise factor in [0, 1] of digital intensity ``I`` (see :class:`DvsParams`)."""
    intensity = np.asarray(intensity, np.float32)
    if curve == "reinhard_gamma":
        x = np.maximum(intensity * np.float32(1 / 255), 0)
        return (x / (x + 1)) ** np.float32(1 / 2.2)
    if curve == "affine":
        return (intensity + np.float32(20)) * np.float32(1 / 275)
    raise UsageError(f"unknown DVS intensity curve {curve!r}; use 'reinhard_gamma' or 'affine'")


class DvsPixels:
    """State of every DVS pixel; feed it the radiance each pixel sees at increasing times."""

    def __init__(self, params: DvsParams, height: int, width: int, seed: int) -> None:
        self.params = params
        self.shape = (height, width)
        self._rng = np.random.default_rng([seed, 0xD75])
        size = height * width
        self.threshold_on = self._draw_thresholds(params.threshold_on, size)
        self.threshold_off = self._draw_thresholds(params.threshold_off, size)
        self.leak_scale = 10 ** (params.rate_cov_decades * self._rng.standard_normal(size))
        self._leak_per_s = (params.leak_rate_hz * self.leak_scale * self.threshold_on).astype(
            np.float32
        )
        self._time_us: int | None = None
        self._lowpass = np.zeros(size, np.float32)
        self._base = np.zeros(size, np.float32)
        self._last_event_us = np.zeros(size, np.int64)

    def _draw_thresholds(self, nominal: float, size: int) -> np.ndarray:
        drawn = self._rng.normal(nominal, self.params.threshold_sigma, size)
        return np.maximum(drawn, _MIN_THRESHOLD).astype(np.float32)

    def step(self, radiance: np.ndarray, time_us: int) -> np.ndarray:
        """Advance to ``time_us`` with the pixels seeing ``radiance`` ``(H, W)``; return events.

        The first call only initialises the pixels (no events).

        Raises:
            UsageError: wrong image shape, or a time not after the previous one.
        """
        radiance = np.asarray(radiance)
        if radiance.shape != self.shape:
            raise UsageError(f"DVS input has shape {radiance.shape}, the array is {self.shape}")
        intensity = 255.0 * radiance.ravel()
        log_intensity = lin_log(intensity, self.params.linlog_threshold)
        if self._time_us is None:
            self._lowpass[:] = log_intensity
            self._base[:] = log_intensity
            self._last_event_us[:] = time_us - self.params.refractory_us - 1
            self._time_us = int(time_us)
            return np.empty(0, EVENT_DTYPE)
        if time_us <= self._time_us:
            raise UsageError(f"DVS time {time_us} µs is not after the previous {self._time_us} µs")
        start_us, self._time_us = self._time_us, int(time_us)
        dt_s = (time_us - start_us) * 1e-6
        factor = intensity_factor(intensity, self.params.intensity_curve)
        signal = self._filter(log_intensity, factor, dt_s)
        self._leak(dt_s)
        events = self._fire(signal, start_us, int(time_us))
        noise = self._shot_noise(signal, factor, dt_s, int(time_us))
        return np.concatenate([events, noise]) if len(noise) else events

    def _filter(self, log_intensity: np.ndarray, factor: np.ndarray, dt_s: float) -> np.ndarray:
        if self.params.cutoff_hz <= 0:
            self._lowpass[:] = log_intensity
            return self._lowpass
        previous = self._lowpass.copy()
        epsilon = np.minimum(1, factor * np.float32(dt_s * 2 * np.pi * self.params.cutoff_hz))
        self._lowpass += epsilon * (log_intensity - self._lowpass)
        return previous if self.params.one_step_delay else self._lowpass

    def _leak(self, dt_s: float) -> None:
        if self.params.leak_rate_hz <= 0:
            return
        jitter = self._rng.standard_normal(self._base.size, np.float32)
        jitter *= np.float32(-self.params.leak_jitter)
        jitter += 1
        self._base -= self._leak_per_s * jitter * np.float32(dt_s)

    def _fire(self, signal: np.ndarray, start_us: int, end_us: int) -> np.ndarray:
        difference = signal - self._base
        count_on = np.floor(np.maximum(difference, 0) / self.threshold_on).astype(np.int64)
        count_off = np.floor(np.maximum(-difference, 0) / self.threshold_off).astype(np.int64)
        active = np.flatnonzero(count_on + count_off)
        if len(active) == 0:
            return np.empty(0, EVENT_DTYPE)
        counts = (count_on + count_off)[active]
        polarity = np.where(count_on[active] > 0, 1, -1).astype(np.int8)
        steps = int(counts.max())
        refractory = self.params.refractory_us > (end_us - start_us) / steps
        emitted = np.zeros(len(active), np.int64)
        times, pixels, signs = [], [], []
        for index in range(steps):
            stamp = start_us + ((index + 1) * (end_us - start_us)) // steps
            firing = np.flatnonzero(counts > index)
            if refractory:
                rested = stamp - self._last_event_us[active[firing]] > self.params.refractory_us
                firing = firing[rested]
            self._last_event_us[active[firing]] = stamp
            emitted[firing] += 1
            times.append(np.full(len(firing), stamp, np.int64))
            pixels.append(active[firing])
            signs.append(polarity[firing])
        step_on = np.where(polarity > 0, emitted, 0) * self.threshold_on[active]
        step_off = np.where(polarity < 0, emitted, 0) * self.threshold_off[active]
        self._base[active] += step_on - step_off
        return self._pack(np.concatenate(times), np.concatenate(pixels), np.concatenate(signs))

    def _shot_noise(
        self, signal: np.ndarray, factor: np.ndarray, dt_s: float, end_us: int
    ) -> np.ndarray:
        """Shot-noise events, stamped at the end of the step.

        Each pixel fires ON with probability ``p * on_ratio`` and OFF with ``p * off_ratio``;
        drawn as a binomial number of candidates at the largest probability, each kept with its
        own probability (the same distribution, without a random draw per pixel).
        """
        rate = self.params.shot_noise_rate_hz
        if rate <= 0:
            return np.empty(0, EVENT_DTYPE)
        on_ratio = self.params.threshold_on / self.threshold_on
        off_ratio = self.params.threshold_off / self.threshold_off
        bound = rate / 2 * dt_s * float(np.max(on_ratio + off_ratio))
        candidates = self._rng.binomial(self._base.size, min(bound, 1.0))
        pixels = np.sort(self._rng.choice(self._base.size, candidates, replace=False))
        chance = rate / 2 * dt_s * (1 - 0.75 * factor[pixels])
        uniform = self._rng.random(len(pixels)) * bound
        on = uniform < chance * on_ratio[pixels]
        off = ~on & (uniform < chance * (on_ratio[pixels] + off_ratio[pixels]))
        pixels, on = pixels[on | off], on[on | off]
        self._base[pixels] = signal[pixels]
        return self._pack(
            np.full(len(pixels), end_us, np.int64), pixels, np.where(on, 1, -1).astype(np.int8)
        )

    def _pack(self, times: np.ndarray, pixels: np.ndarray, polarity: np.ndarray) -> np.ndarray:
        events = np.empty(len(times), EVENT_DTYPE)
        events["t"] = times
        events["y"], events["x"] = np.divmod(pixels, self.shape[1])
        events["p"] = polarity
        return events
