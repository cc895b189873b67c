"""Capture side of seecap: DAVIS over USB, AEDAT files, the emulator, sessions, bins and poses.

This package never imports torch.
"""

from davis_io.errors import SeecapError, describe_error

__version__ = "0.1.0"

__all__ = ["SeecapError", "__version__", "describe_error"]
