"""Capture side of seecap: DAVIS over USB, AEDAT files, the emulator, sessions, bins and poses.

This package never imports torch.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
