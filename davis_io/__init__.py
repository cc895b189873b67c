"""Capture side of seecap: DAVIS over USB, AEDAT files, the emulator, sessions, bins and poses.

This package never imports torch.
"""

from davis_io.errors import SeecapError

__version__ = "0.1.0"

__all__ = ["SeecapError", "__version__"]
