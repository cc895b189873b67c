"""A session's sharp latent frames and their poses as a nerfstudio / instant-ngp data folder."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from davis_io.errors import UsageError
from davis_io.geometry import nerfstudio_transforms
from davis_io.poses.colmap import model_points
from davis_io.session import DEFAULT_BINS, Session

__all__ = ["export_nerfstudio", "latent_frame_name", "write_ply"]

POINTS_NAME = "sparse_pc.ply"
"""COLMAP's points beside ``transforms.json`` (its ``ply_file_path``), named as nerfstudio does."""

POINT_GREY = 128
"""Colour of every point: the latent frames are grey and COLMAP keeps no colour for them."""


def latent_frame_name(frame: int, point: int) -> str:
    """File name of frame ``frame``'s latent image at latent time point ``point``."""
    return f"{frame:04d}_{point}.png"


def export_nerfstudio(session_dir: Path | str, out_dir: Path | str, b: int = DEFAULT_BINS) -> Path:
    """Write the registered latent frames and a ``transforms.json`` of their poses.

    ``out_dir/images/*.png`` are the EDI latent frames COLMAP registered, ready for another
    NeRF tool to train on; ``out_dir/transforms.json`` gives their poses, the intrinsics and the
    distortion, and ``ply_file_path`` names COLMAP's 3-D points (``sparse_pc.ply``, for the
    methods that start from them).

    Returns:
        The ``transforms.json`` written.

    Raises:
        UsageError: the session has no poses for ``b`` (or their latent frames are gone).
    """
    session_dir, out_dir = Path(session_dir), Path(out_dir)
    with Session.open(session_dir) as session:
        poses = session.poses(b)
        size = (session.height, session.width)
    images = session_dir / "colmap" / "images"
    if poses is None or not images.is_dir():
        raise UsageError(
            f"{session_dir}: no poses for b={b} with their latent frames; run `seecap poses "
            f"{session_dir} --bins {b}` first"
        )
    (out_dir / "images").mkdir(parents=True, exist_ok=True)
    names, c2w = [], []
    for frame, point in zip(*poses.registered.nonzero(), strict=True):
        name = latent_frame_name(int(frame), int(point))
        shutil.copyfile(images / name, out_dir / "images" / name)
        names.append(f"images/{name}")
        c2w.append(poses.c2w[frame, point])
    payload = nerfstudio_transforms(c2w, poses.intrinsics, poses.distortion, size, names)
    model = _kept_model(session_dir)
    if model is not None:
        write_ply(out_dir / POINTS_NAME, model_points(model))
        payload["ply_file_path"] = POINTS_NAME
    path = out_dir / "transforms.json"
    path.write_text(json.dumps(payload, indent=1))
    return path


def _kept_model(session_dir: Path) -> Path | None:
    """The folder of the COLMAP model that gave the poses (``colmap/report.json``), or None."""
    try:
        report = json.loads((session_dir / "colmap" / "report.json").read_text())
    except (OSError, ValueError):
        return None
    folder = session_dir / "colmap" / str(report.get("sparse_model", ""))
    return folder if report.get("sparse_model") and (folder / "points3D.bin").is_file() else None


def write_ply(path: Path, points: np.ndarray) -> Path:
    """Write ``(N, 3)`` points as an ASCII PLY with grey vertex colours."""
    points = np.asarray(points, np.float64).reshape(-1, 3)
    header = [
        "ply",
        "format ascii 1.0",
        f"element vertex {len(points)}",
        "property float x",
        "property float y",
        "property float z",
        "property uchar red",
        "property uchar green",
        "property uchar blue",
        "end_header",
    ]
    rows = [f"{x:.6g} {y:.6g} {z:.6g} {POINT_GREY} {POINT_GREY} {POINT_GREY}" for x, y, z in points]
    path.write_text("\n".join(header + rows) + "\n")
    return path
