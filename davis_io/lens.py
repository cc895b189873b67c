"""A camera's lens: pinhole intrinsics and OpenCV distortion, read from the files users have.

Pixel centres are at integer coordinates (OpenCV's convention and the session's). The
distortion follows OpenCV's model: ``k1, k2, p1, p2`` and optionally ``k3`` and the rational
terms ``k4, k5, k6``, applied to normalised coordinates ``(x / z, y / z)``; a lens without
coefficients is a pinhole. The same numbers mean the same lens in DV's calibration files,
OpenCV's and COLMAP's ``OPENCV`` / ``FULL_OPENCV`` models (COLMAP puts pixel centres at +0.5).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from davis_io.errors import UsageError

__all__ = ["COEFFICIENT_NAMES", "Lens", "read_camera_calibration", "write_camera_calibration"]

COEFFICIENT_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
"""OpenCV's distortion coefficients, in its order."""

_COLMAP_PIXEL_OFFSET = 0.5
"""COLMAP puts pixel ``i``'s centre at ``i + 0.5``."""

_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)

_COLMAP_MODELS = {
    # name: parameter names, in COLMAP's order
    "SIMPLE_PINHOLE": ("f", "cx", "cy"),
    "PINHOLE": ("fx", "fy", "cx", "cy"),
    "SIMPLE_RADIAL": ("f", "cx", "cy", "k1"),
    "RADIAL": ("f", "cx", "cy", "k1", "k2"),
    "OPENCV": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"),
    "FULL_OPENCV": ("fx", "fy", "cx", "cy", *COEFFICIENT_NAMES),
}


@dataclass(frozen=True)
class Lens:
    """Intrinsics and distortion of one camera.

    Attributes:
        width: image columns the calibration is for.
        height: image rows.
        fx: horizontal focal length, pixels.
        fy: vertical focal length, pixels.
        cx: principal point column, pixels (pixel centres at integers).
        cy: principal point row, pixels.
        distortion: OpenCV coefficients ``k1, k2, p1, p2[, k3[, k4, k5, k6]]``, trailing zeros
            dropped (empty: a pinhole).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for name in ("fx", "fy", "cx", "cy"):
            object.__setattr__(self, name, float(getattr(self, name)))
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        values = [self.fx, self.fy, self.cx, self.cy, *self.distortion]
        if not all(np.isfinite(values)) or self.fx <= 0 or self.fy <= 0:
            raise UsageError(
                f"a lens needs finite values and positive focal lengths, got fx {self.fx}, "
                f"fy {self.fy}, cx {self.cx}, cy {self.cy}, distortion {list(self.distortion)}"
            )
        if len(self.distortion) > len(COEFFICIENT_NAMES):
            raise UsageError(
                f"{len(self.distortion)} distortion coefficients; OpenCV's model has at most "
                f"{len(COEFFICIENT_NAMES)} ({', '.join(COEFFICIENT_NAMES)})"
            )
        coefficients = [float(c) for c in self.distortion]
        while coefficients and coefficients[-1] == 0.0:
            coefficients.pop()
        object.__setattr__(self, "distortion", tuple(coefficients))

    @classmethod
    def pinhole(cls, width: int, height: int, intrinsics) -> Lens:
        """A lens without distortion from ``(fx, fy, cx, cy)``."""
        fx, fy, cx, cy = (float(v) for v in np.asarray(intrinsics, float).reshape(4))
        return cls(int(width), int(height), fx, fy, cx, cy)

    def with_distortion(self, distortion) -> Lens:
        """This lens's intrinsics with other distortion coefficients."""
        return Lens(self.width, self.height, self.fx, self.fy, self.cx, self.cy, tuple(distortion))

    def close_to(self, other: Lens, tolerance: float = 1e-6) -> bool:
        """Whether ``other`` has the same intrinsics and distortion, to ``tolerance``."""
        ours, theirs = np.zeros(len(COEFFICIENT_NAMES)), np.zeros(len(COEFFICIENT_NAMES))
        ours[: len(self.distortion)] = self.distortion
        theirs[: len(other.distortion)] = other.distortion
        return np.allclose(self.intrinsics, other.intrinsics, rtol=tolerance) and np.allclose(
            ours, theirs, rtol=tolerance, atol=tolerance * 1e-3
        )

    def corner_shift_px(self) -> float:
        """How far the distortion moves the image's corners from where a pinhole puts them."""
        corners = np.array(
            [[0, 0], [self.width - 1, 0], [0, self.height - 1], [self.width - 1, self.height - 1]],
            np.float64,
        )
        pinhole = self.normalised(corners) * self.intrinsics[:2] + self.intrinsics[2:]
        return float(np.abs(pinhole - corners).max())

    @property
    def intrinsics(self) -> np.ndarray:
        """``(4,)`` fx, fy, cx, cy."""
        return np.array([self.fx, self.fy, self.cx, self.cy], np.float64)

    @property
    def is_pinhole(self) -> bool:
        """Whether the lens has no distortion."""
        return not self.distortion

    @property
    def coefficients(self) -> np.ndarray:
        """The distortion as OpenCV takes it: 4, 5 or 8 coefficients."""
        count = len(self.distortion)
        size = 4 if count <= 4 else 5 if count == 5 else 8
        out = np.zeros(size)
        out[:count] = self.distortion
        return out

    @property
    def matrix(self) -> np.ndarray:
        """The ``3x3`` camera matrix."""
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1]], np.float64)

    def normalised(self, pixels: np.ndarray) -> np.ndarray:
        """``(N, 2)`` undistorted ``(x / z, y / z)`` of the rays through ``(N, 2)`` pixels."""
        points = np.asarray(pixels, np.float64).reshape(-1, 1, 2)
        if self.is_pinhole:
            return ((points[:, 0] - self.intrinsics[2:]) / self.intrinsics[:2]).reshape(-1, 2)
        out = cv2.undistortPoints(
            points, self.matrix, self.coefficients, None, None, None, _UNDISTORT_CRITERIA
        )
        return out.reshape(-1, 2)

    def project(self, normalised: np.ndarray) -> np.ndarray:
        """``(N, 2)`` pixels where rays of undistorted ``(x / z, y / z)`` land."""
        xy = np.asarray(normalised, np.float64).reshape(-1, 2)
        points = np.concatenate([xy, np.ones((len(xy), 1))], axis=1)
        pixels, _ = cv2.projectPoints(
            points, np.zeros(3), np.zeros(3), self.matrix, self.coefficients
        )
        return pixels.reshape(-1, 2)

    def pixel_rays(self) -> np.ndarray:
        """``(H, W, 2)`` undistorted ``(x / z, y / z)`` of every pixel's ray."""
        rows, cols = np.mgrid[0 : self.height, 0 : self.width]
        pixels = np.stack([cols.ravel(), rows.ravel()], axis=1)
        return self.normalised(pixels).reshape(self.height, self.width, 2)

    def summary(self) -> str:
        """One line: the intrinsics and the distortion's coefficients."""
        text = (
            f"{self.width}x{self.height}, fx {self.fx:.2f} fy {self.fy:.2f} "
            f"cx {self.cx:.2f} cy {self.cy:.2f} px"
        )
        if self.is_pinhole:
            return text + ", no distortion"
        named = ", ".join(
            f"{n} {c:+.4g}" for n, c in zip(COEFFICIENT_NAMES, self.distortion, strict=False)
        )
        return f"{text}, {named}"

    def to_json(self) -> dict:
        """The lens as a JSON object (read back by :meth:`from_json`)."""
        return {
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            **dict(zip(COEFFICIENT_NAMES, self.distortion, strict=False)),
        }

    @classmethod
    def from_json(cls, values: dict, where: str = "lens") -> Lens:
        """The lens of a JSON object with width, height, fx, fy, cx, cy and any of k1 .. k6.

        Raises:
            UsageError: a key is missing or a value is not a number.
        """
        try:
            named = {key: float(values[key]) for key in COEFFICIENT_NAMES if key in values}
            distortion = [named.get(key, 0.0) for key in COEFFICIENT_NAMES]
            return cls(
                int(values["width"]),
                int(values["height"]),
                *(float(values[key]) for key in ("fx", "fy", "cx", "cy")),
                tuple(distortion),
            )
        except (KeyError, TypeError, ValueError) as error:
            raise UsageError(
                f"{where}: a lens needs width, height, fx, fy, cx, cy (pixels) and optionally "
                f"{', '.join(COEFFICIENT_NAMES)} ({type(error).__name__}: {error})"
            ) from None

    def for_size(self, width: int, height: int, where: str) -> Lens:
        """This lens, checked to be for a ``width`` x ``height`` sensor.

        Raises:
            UsageError: the calibration is for another image size.
        """
        if (self.width, self.height) != (width, height):
            raise UsageError(
                f"{where}: the calibration is for {self.width}x{self.height} images, the "
                f"camera's are {width}x{height}; calibrate this camera at its full resolution"
            )
        return self


def read_camera_calibration(path: Path | str, width: int, height: int) -> Lens:
    """The lens a calibration file states, for a ``width`` x ``height`` sensor.

    Reads DV's and OpenCV's calibration files (OpenCV FileStorage XML or YAML, with
    ``camera_matrix`` and ``distortion_coefficients`` at the top or under one camera's node, as
    DV writes them), COLMAP's ``cameras.txt`` (its first camera) and JSON with fx, fy, cx, cy
    and optionally k1 .. k6 (size optional).

    Raises:
        UsageError: the file cannot be read, holds no camera, a fisheye model or a camera of
            another image size.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such calibration file")
    suffix = path.suffix.lower()
    if suffix == ".json":
        lens = _json_lens(path, width, height)
    elif suffix == ".txt":
        lens = _colmap_lens(path)
    elif suffix in (".xml", ".yaml", ".yml"):
        lens = _opencv_lens(path, width, height)
    else:
        raise UsageError(
            f"{path}: not a calibration file seecap reads; give DV's or OpenCV's XML or YAML, "
            "COLMAP's cameras.txt or JSON with fx, fy, cx, cy"
        )
    return lens.for_size(width, height, str(path))


def write_camera_calibration(lens: Lens, path: Path | str, camera_name: str) -> Path:
    """Write ``lens`` as DV writes a camera's calibration.

    An OpenCV FileStorage file (XML or YAML by its suffix) with the camera's values under a node
    named ``camera_name``.
    """
    path = Path(path)
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        storage.startWriteStruct(camera_name, cv2.FileNode_MAP)
        storage.write("camera_matrix", lens.matrix)
        storage.write("distortion_coefficients", lens.coefficients.reshape(1, -1))
        storage.write("image_width", lens.width)
        storage.write("image_height", lens.height)
        storage.write("use_fisheye_model", 0)
        storage.endWriteStruct()
    finally:
        storage.release()
    return path


def _json_lens(path: Path, width: int, height: int) -> Lens:
    try:
        values = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise UsageError(f"{path}: not readable JSON ({error})") from None
    if not isinstance(values, dict):
        raise UsageError(f"{path}: a JSON calibration is an object with fx, fy, cx, cy")
    return Lens.from_json({"width": width, "height": height, **values}, str(path))


def _colmap_lens(path: Path) -> Lens:
    try:
        lines = path.read_text().splitlines()
    except (OSError, UnicodeDecodeError) as error:
        raise UsageError(f"{path}: cannot read it ({error})") from None
    cameras = [line.split() for line in lines if line.strip() and not line.startswith("#")]
    if not cameras:
        raise UsageError(f"{path}: no camera in this cameras.txt")
    words = cameras[0]
    model = words[1] if len(words) > 1 else ""
    names = _COLMAP_MODELS.get(model)
    if names is None or len(words) != 4 + len(names):
        raise UsageError(
            f"{path}: camera line {' '.join(words)!r} is not one of COLMAP's "
            f"{', '.join(_COLMAP_MODELS)} models with its parameters"
        )
    try:
        width, height = int(words[2]), int(words[3])
        values = dict(zip(names, (float(word) for word in words[4:]), strict=False))
    except ValueError as error:
        raise UsageError(f"{path}: camera line {' '.join(words)!r}: {error}") from None
    if "f" in values:
        values["fx"] = values["fy"] = values.pop("f")
    values["cx"] -= _COLMAP_PIXEL_OFFSET
    values["cy"] -= _COLMAP_PIXEL_OFFSET
    return Lens.from_json({"width": width, "height": height, **values}, str(path))


def _opencv_lens(path: Path, width: int, height: int) -> Lens:
    try:
        storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error as error:
        raise UsageError(f"{path}: OpenCV cannot read it ({error.msg.strip()})") from None
    try:
        node = _camera_node(storage.root(), path)
        matrix = node.getNode("camera_matrix").mat()
        coefficients = node.getNode("distortion_coefficients").mat()
        if node.getNode("use_fisheye_model").real():
            raise UsageError(
                f"{path}: a fisheye calibration; seecap takes OpenCV's standard model "
                "(calibrate again without the fisheye option)"
            )
        size = [node.getNode(key) for key in ("image_width", "image_height")]
        if not any(entry.empty() for entry in size):
            width, height = int(size[0].real()), int(size[1].real())
    finally:
        storage.release()
    if matrix is None or matrix.shape != (3, 3):
        raise UsageError(f"{path}: camera_matrix is not a 3x3 matrix")
    distortion = () if coefficients is None else tuple(np.asarray(coefficients).ravel())
    return Lens(width, height, matrix[0, 0], matrix[1, 1], matrix[0, 2], matrix[1, 2], distortion)


def _camera_node(root, path: Path):
    """The node holding ``camera_matrix``: the root, or the first camera's (DV's layout)."""
    if not root.getNode("camera_matrix").empty():
        return root
    for key in root.keys():
        node = root.getNode(key)
        if node.isMap() and not node.getNode("camera_matrix").empty():
            return node
    raise UsageError(
        f"{path}: no camera_matrix in it, at its top or under a camera's name; give the file "
        "DV's or OpenCV's camera calibration writes"
    )
