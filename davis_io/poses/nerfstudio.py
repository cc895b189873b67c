"""A session's sharp latent frames and their poses as a nerfstudio / instant-ngp data folder."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from davis_io.errors import UsageError
from davis_io.geometry import nerfstudio_transforms
from davis_io.session import DEFAULT_BINS, Session

__all__ = ["export_nerfstudio", "latent_frame_name"]


def latent_frame_name(frame: int, point: int) -> str:
    """File name of frame ``frame``'s latent image at latent time point ``point``."""
    return f"{frame:04d}_{point}.png"


def export_nerfstudio(session_dir: Path | str, out_dir: Path | str, b: int = DEFAULT_BINS) -> Path:
    """Write the registered latent frames and a ``transforms.json`` of their poses.

    ``out_dir/images/*.png`` are the EDI latent frames COLMAP registered, ready for another
    NeRF tool to train on; ``out_dir/transforms.json`` gives their poses and the intrinsics.

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
    path = out_dir / "transforms.json"
    path.write_text(json.dumps(payload, indent=1))
    return path
