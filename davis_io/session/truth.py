"""The ``truth/`` folder of a session: what really happened in an emulated recording.

Only scoring and the ``oracle`` / ``white-box`` fits read it; bins, calibration, poses and
``full`` fits never do, as a real camera has none. Layout::

    truth/truth.h5
        attrs: scene, seed, crf (response family), exposure_us (training exposure),
               test_exposures_s (5: x1/16, x1/4, x1, x4, x16 of it), color_filter,
               extent (largest distance between two training camera rest positions, metres;
               the view spacing when there is one view),
               gain_per_s (response input = gain * radiance * exposure_s),
               depth_range_m (nearest and farthest depth in the mid-exposure training views),
               camera (JSON: the emulator settings that remake this recording),
               sensor (JSON: the sensor's true values: the DVS pixel model as drawn, the
               thresholds' median and harmonic mean over the pixels, latency and event delay,
               the response with its parameters)
        /intrinsics          float64 (4,)            fx, fy, cx, cy (pixel centres at integers)
        /train/time_us       int64   (F, S)          sub-frame times of each training exposure
        /train/c2w           float64 (F, S, 4, 4)    true poses at those times (OpenCV axes)
        /train/sharp_hdr     float32 (F, H, W, C)    linear radiance at mid-exposure
        /test/c2w            float64 (T, 4, 4)       held-out views
        /test/hdr            float32 (T, H, W, C)    sharp linear radiance
        /test/ldr            uint8   (T, 5, H, W, C) through the true response, full channels
        /crf/log_exposure    float64 (K,)            ln(radiance * exposure_s)
        /crf/value           float64 (K,)            LDR value in [0, 1]
        /path/time_us        int64   (N,)            every millisecond of the recording
        /path/c2w            float64 (N, 4, 4)       true poses then (see Truth.c2w_at)
        /sensor/threshold_on float32 (H, W)          each DVS pixel's ON threshold
        /sensor/threshold_off float32 (H, W)         and OFF threshold
    truth/test/hdr/{i:03d}.exr       float32 OpenEXR (RGB, or Y for monochrome)
    truth/test/ldr/x{factor}/{i:03d}.png   8-bit, factor in 1_16, 1_4, 1, 4, 16

C is 3 (RGB) for colour sensors and 1 (luminance) for monochrome ones.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import h5py
import numpy as np
import OpenEXR

from davis_io.errors import SessionError
from davis_io.geometry import interpolate_poses
from davis_io.session.calibration import SensorCalibration
from davis_io.session.layout import FILE_FORMAT
from davis_io.types import ColorFilter

__all__ = ["TEST_EXPOSURE_FACTORS", "TRUTH_DIR", "Truth", "load_truth", "save_truth"]

TRUTH_DIR = "truth"
"""Name of the truth folder inside a session folder."""

TEST_EXPOSURE_FACTORS = (1 / 16, 1 / 4, 1.0, 4.0, 16.0)
"""The paper's exposure bracket, as multiples of the training exposure."""

_FACTOR_NAMES = ("1_16", "1_4", "1", "4", "16")
_ARRAYS = {
    "intrinsics": "intrinsics",
    "train_time_us": "train/time_us",
    "train_c2w": "train/c2w",
    "train_sharp_hdr": "train/sharp_hdr",
    "test_c2w": "test/c2w",
    "test_hdr": "test/hdr",
    "test_ldr": "test/ldr",
    "crf_log_exposure": "crf/log_exposure",
    "crf_value": "crf/value",
    "path_time_us": "path/time_us",
    "path_c2w": "path/c2w",
    "pixel_threshold_on": "sensor/threshold_on",
    "pixel_threshold_off": "sensor/threshold_off",
}
_JSON_ATTRS = ("camera", "sensor")
_OPTIONAL = ("pixel_threshold_on", "pixel_threshold_off")
"""Arrays a truth written before they were recorded lacks (then empty)."""


@dataclass
class Truth:
    """What really happened in an emulated recording (shapes in the module docstring)."""

    scene: str
    seed: int
    crf: str
    exposure_us: int
    test_exposures_s: np.ndarray
    color_filter: ColorFilter
    extent: float
    gain_per_s: float
    depth_range_m: np.ndarray
    intrinsics: np.ndarray
    train_time_us: np.ndarray
    train_c2w: np.ndarray
    train_sharp_hdr: np.ndarray
    test_c2w: np.ndarray
    test_hdr: np.ndarray
    test_ldr: np.ndarray
    crf_log_exposure: np.ndarray
    crf_value: np.ndarray
    path_time_us: np.ndarray
    path_c2w: np.ndarray
    pixel_threshold_on: np.ndarray
    pixel_threshold_off: np.ndarray
    camera: dict = field(default_factory=dict)
    sensor: dict = field(default_factory=dict)

    def sensor_calibration(self) -> SensorCalibration:
        """What a perfect calibration would measure: the sensor's true values (white-box fits).

        The median pixel's thresholds with every pixel's factor, the events' true delay, the
        photoreceptor's cut-off, the pixels' dead time, the response's black and clip levels,
        its table and (linear frames) their noise.

        Raises:
            SessionError: this truth does not record its sensor (written by an older version).
        """
        if not self.sensor or self.pixel_threshold_on.size == 0:
            raise SessionError(
                "this session's truth does not record its sensor's values; record it again"
            )
        response = self.sensor["response"]
        medians = [float(np.median(t)) for t in (self.pixel_threshold_on, self.pixel_threshold_off)]
        clipped = self.crf_value < np.max(self.crf_value)
        noise = self.sensor.get("frame_noise", {})
        return SensorCalibration(
            threshold_on=medians[0],
            threshold_off=medians[1],
            latency_us=int(self.sensor["event_delay_us"]),
            black_level=float(response.get("black", 0.0)),
            saturation=float(response.get("saturation", 1.0)),
            response_linear=response["family"] == "linear",
            cutoff_hz=float(self.sensor["dvs"]["cutoff_hz"]),
            dead_time_us=int(self.sensor.get("dead_time_us", 0)),
            noise_gain=float(noise.get("gain", 0.0)),
            noise_floor=float(noise.get("floor", 0.0)),
            response_value=self.crf_value[clipped],
            response_log_exposure=self.crf_log_exposure[clipped],
            pixel_factor_on=(self.pixel_threshold_on / medians[0]).astype(np.float32),
            pixel_factor_off=(self.pixel_threshold_off / medians[1]).astype(np.float32),
            source="truth",
            method="the emulated sensor's true values",
        )

    def c2w_at(self, times_us: np.ndarray) -> np.ndarray:
        """True camera-to-world ``(Q, 4, 4)`` at any times ``(Q,)`` µs of the recording.

        Interpolated (slerp and linear) from the path sampled every millisecond; with the
        shake's frequencies (below 6 Hz) the error stays under 1e-5 rad (0.003 px at 280 px focal).
        """
        return interpolate_poses(self.path_time_us, self.path_c2w, np.asarray(times_us))


def _write_exr(path: Path, image: np.ndarray) -> None:
    name = "RGB" if image.shape[-1] == 3 else "Y"
    pixels = np.ascontiguousarray(image if name == "RGB" else image[..., 0], np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {name: pixels}).write(str(path))


def save_truth(truth: Truth, folder: str | Path) -> Path:
    """Write ``truth.h5`` and the viewable EXR and PNG files into ``folder`` (the ``truth/`` dir).

    Returns:
        The folder.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with h5py.File(folder / "truth.h5", "w", libver=FILE_FORMAT) as h5:
        h5.attrs.update(
            {
                "scene": truth.scene,
                "seed": truth.seed,
                "crf": truth.crf,
                "exposure_us": truth.exposure_us,
                "test_exposures_s": truth.test_exposures_s,
                "color_filter": truth.color_filter.value,
                "extent": truth.extent,
                "gain_per_s": truth.gain_per_s,
                "depth_range_m": truth.depth_range_m,
                **{name: json.dumps(getattr(truth, name)) for name in _JSON_ATTRS},
            }
        )
        for attribute, path in _ARRAYS.items():
            h5.create_dataset(
                path, data=getattr(truth, attribute), compression="gzip", compression_opts=1
            )
    for index, hdr in enumerate(truth.test_hdr):
        (folder / "test" / "hdr").mkdir(parents=True, exist_ok=True)
        _write_exr(folder / "test" / "hdr" / f"{index:03d}.exr", hdr)
        for factor, ldr in zip(_FACTOR_NAMES, truth.test_ldr[index], strict=True):
            ldr_dir = folder / "test" / "ldr" / f"x{factor}"
            ldr_dir.mkdir(parents=True, exist_ok=True)
            cv2.imwrite(
                str(ldr_dir / f"{index:03d}.png"), ldr[..., ::-1] if ldr.shape[-1] == 3 else ldr
            )
    return folder


def load_truth(folder: str | Path) -> Truth:
    """Read a ``truth/`` folder (or a session folder that contains one).

    Raises:
        SessionError: no ``truth.h5`` there, or it lacks a field.
    """
    folder = Path(folder)
    if not (folder / "truth.h5").exists() and (folder / TRUTH_DIR / "truth.h5").exists():
        folder = folder / TRUTH_DIR
    path = folder / "truth.h5"
    if not path.exists():
        raise SessionError(f"{path}: no ground truth here; only emulated sessions have truth/")
    try:
        with h5py.File(path, "r") as h5:
            attrs = dict(h5.attrs)
            arrays = {
                attribute: h5[name][()] if name in h5 or attribute not in _OPTIONAL else np.zeros(0)
                for attribute, name in _ARRAYS.items()
            }
        return Truth(
            scene=str(attrs["scene"]),
            seed=int(attrs["seed"]),
            crf=str(attrs["crf"]),
            exposure_us=int(attrs["exposure_us"]),
            test_exposures_s=np.asarray(attrs["test_exposures_s"], np.float64),
            color_filter=ColorFilter(str(attrs["color_filter"])),
            extent=float(attrs["extent"]),
            gain_per_s=float(attrs["gain_per_s"]),
            depth_range_m=np.asarray(attrs["depth_range_m"], np.float64),
            **{name: json.loads(attrs.get(name, "{}")) for name in _JSON_ATTRS},
            **arrays,
        )
    except KeyError as missing:
        raise SessionError(f"{path}: missing {missing}; rewrite it with save_truth") from None
    except (OSError, json.JSONDecodeError) as error:
        raise SessionError(f"{path}: cannot be read ({error})") from None
