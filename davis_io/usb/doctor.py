"""Health checks of the capture machine: libusb, camera access, udev rule, libraries, GPU, disk."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import usb.backend

from davis_io.errors import DavisIOError
from davis_io.usb.discovery import default_backend, list_cameras
from davis_io.usb.udev import RULES_DIR, install_hint, installed_rule_path

__all__ = ["Check", "run_checks"]

_MIN_FREE_BYTES = 2 * 1024**3
"""Below this much free space a recording of a few minutes may not fit."""
_NVIDIA_GPUS = Path("/proc/driver/nvidia/gpus")


@dataclass(frozen=True)
class Check:
    """One line of ``seecap doctor``: what was checked, whether it passed, and the detail."""

    name: str
    ok: bool
    detail: str


def _libusb_check() -> tuple[Check, usb.backend.IBackend | None]:
    try:
        backend = default_backend()
    except DavisIOError as error:
        return Check("libusb", False, str(error)), None
    return Check("libusb", True, f"loaded ({type(backend).__module__})"), backend


def _camera_checks(backend: usb.backend.IBackend | None) -> list[Check]:
    if backend is None:
        return [Check("cameras", False, "cannot look for cameras without libusb")]
    cameras = list_cameras(backend)
    if not cameras:
        return [Check("cameras", True, "none attached (permissions checked when one is)")]
    return [
        Check(
            f"camera {c.model} {c.serial or '?'} (bus {c.bus} address {c.address})",
            c.usable,
            "opens, versions supported" if c.usable else c.problem,
        )
        for c in cameras
    ]


def _udev_check(rules_dir: Path) -> Check:
    if not Path("/etc/udev").exists():
        return Check("udev rule", True, "no udev on this system (not needed)")
    path = installed_rule_path(rules_dir)
    if path is None:
        return Check("udev rule", False, f"not installed in {rules_dir}; run:\n  {install_hint()}")
    return Check("udev rule", True, f"installed: {path}")


def _module_check(name: str, purpose: str) -> Check:
    found = importlib.util.find_spec(name) is not None
    return Check(
        name,
        found,
        f"importable ({purpose})"
        if found
        else f"not importable; needed for {purpose}: pip install {name}",
    )


_TORCH_DEVICE = (
    "import torch; print(torch.__version__, torch.cuda.is_available(), "
    "torch.cuda.device_count(), torch.version.cuda)"
)
"""What torch itself says of CUDA, asked in a child process (davis_io never imports torch)."""


def _torch_cuda() -> tuple[bool, str]:
    """Whether torch sees a CUDA device, and what it said."""
    try:
        done = subprocess.run(
            [sys.executable, "-c", _TORCH_DEVICE],
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
        )
    except (OSError, subprocess.SubprocessError) as error:
        return False, f"torch could not be asked ({error})"
    version, available, count, cuda = done.stdout.split()
    if available == "True":
        return True, f"torch {version} sees {count} CUDA device(s) (CUDA {cuda})"
    built = "a CPU build" if cuda == "None" else f"built for CUDA {cuda}"
    return False, f"torch {version} ({built}) sees no CUDA device"


def _compute_check() -> Check:
    gpus = sorted(_NVIDIA_GPUS.iterdir()) if _NVIDIA_GPUS.is_dir() else []
    usable, said = _torch_cuda()
    if usable:
        return Check("compute", True, f"{said}; fitting uses the GPU")
    if gpus:
        return Check(
            "compute",
            False,
            f"{len(gpus)} NVIDIA GPU(s) in the driver, but {said}: install a CUDA build of "
            "torch (see the README's Install section) or fit with --device cpu",
        )
    return Check("compute", True, f"{said}; fitting runs on {os.cpu_count()} CPU cores")


def _disk_check(path: Path) -> Check:
    free = shutil.disk_usage(path).free
    detail = f"{free / 1024**3:.1f} GiB free in {path}"
    if free < _MIN_FREE_BYTES:
        return Check("disk", False, f"{detail}; free space before recording")
    return Check("disk", True, detail)


def run_checks(
    path: Path = Path("."),
    *,
    rules_dir: Path = RULES_DIR,
    backend: usb.backend.IBackend | None = None,
) -> list[Check]:
    """Run every check; ``path`` is where sessions will be written.

    Args:
        path: folder whose free disk space matters.
        rules_dir: udev rules folder to look in.
        backend: pyusb backend to use instead of the system's libusb (tests).
    """
    if backend is None:
        libusb, backend = _libusb_check()
    else:
        libusb = Check("libusb", True, f"given backend ({type(backend).__name__})")
    return [
        libusb,
        *_camera_checks(backend),
        _udev_check(rules_dir),
        _module_check("pycolmap", "pose estimation"),
        _module_check("torch", "fitting See-NeRF"),
        _compute_check(),
        _disk_check(path),
    ]
