"""LZ4 frames decoded by the system's liblz4 (frame API, through ctypes) into the caller's array.

python-lz4 returns every block as new bytes, which the caller then copies into place; liblz4's
``LZ4F_decompress`` writes a whole frame, linked blocks and checksums included, straight into a
buffer of ours, in one call that releases the GIL. On DV's event packets that is the difference
between matching dv-processing's decoding speed and trailing it (BENCHMARKS.md). liblz4 is part
of almost every Linux system; where it is missing, :func:`system_liblz4` returns None and the
caller decodes with python-lz4 instead.

The calls and structures are those of ``lz4frame.h`` (LZ4 1.8 and later): a decompression context
from ``LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)``; ``LZ4F_decompress(ctx, dst,
&dstSize, src, &srcSize, &options)`` returns 0 once the frame is complete, a size hint when it
needs more input, or an error code that ``LZ4F_isError`` recognises and ``LZ4F_getErrorName``
names. ``stableDst`` in the options promises that earlier output stays in place, so linked blocks
find their dictionary in our buffer instead of being copied through the context's own.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import weakref

import numpy as np

__all__ = ["NativeFrameDecoder", "system_liblz4"]

_LZ4F_VERSION = 100
_MIN_VERSION = 10_800  # LZ4_versionNumber() of 1.8.0: stableDst and a stable frame API


class _DecompressOptions(ctypes.Structure):
    _fields_ = [
        ("stable_dst", ctypes.c_uint),
        ("skip_checksums", ctypes.c_uint),
        ("reserved1", ctypes.c_uint),
        ("reserved0", ctypes.c_uint),
    ]


@functools.cache
def system_liblz4() -> ctypes.CDLL | None:
    """The system's liblz4 with the frame API declared, or None if there is none (or too old)."""
    name = ctypes.util.find_library("lz4")
    if name is None:
        return None
    try:
        lib = ctypes.CDLL(name)
        if lib.LZ4_versionNumber() < _MIN_VERSION:
            return None
        size_p = ctypes.POINTER(ctypes.c_size_t)
        lib.LZ4F_createDecompressionContext.argtypes = [
            ctypes.POINTER(ctypes.c_void_p),
            ctypes.c_uint,
        ]
        lib.LZ4F_createDecompressionContext.restype = ctypes.c_size_t
        lib.LZ4F_freeDecompressionContext.argtypes = [ctypes.c_void_p]
        lib.LZ4F_freeDecompressionContext.restype = ctypes.c_size_t
        lib.LZ4F_decompress.argtypes = [
            ctypes.c_void_p,
            ctypes.c_void_p,
            size_p,
            ctypes.c_void_p,
            size_p,
            ctypes.POINTER(_DecompressOptions),
        ]
        lib.LZ4F_decompress.restype = ctypes.c_size_t
        lib.LZ4F_isError.argtypes = [ctypes.c_size_t]
        lib.LZ4F_isError.restype = ctypes.c_uint
        lib.LZ4F_getErrorName.argtypes = [ctypes.c_size_t]
        lib.LZ4F_getErrorName.restype = ctypes.c_char_p
    except (OSError, AttributeError):  # not loadable, or a build without the frame API
        return None
    return lib


class NativeFrameDecoder:
    """One liblz4 decompression context, reused from frame to frame (one thread at a time)."""

    def __init__(self, lib: ctypes.CDLL):
        """Create the context on ``lib`` (from :func:`system_liblz4`)."""
        self._lib = lib
        self._options = _DecompressOptions(stable_dst=1)
        self._dst_size = ctypes.c_size_t()
        self._src_size = ctypes.c_size_t()
        self._context = self._new_context()
        self._finalizer = weakref.finalize(self, self._free, lib, self._context)

    def decode_into(self, frame: bytes | memoryview, out: np.ndarray) -> int:
        """Decompress the complete LZ4 frame ``frame`` into ``out`` (uint8, contiguous).

        Returns:
            The number of bytes written to the start of ``out``.

        Raises:
            ValueError: the frame is corrupt, incomplete, followed by other bytes, or holds more
                than ``out`` can take.
        """
        self._dst_size.value, self._src_size.value = out.nbytes, len(frame)
        status = self._lib.LZ4F_decompress(
            self._context,
            out.ctypes.data,
            ctypes.byref(self._dst_size),
            np.frombuffer(frame, np.uint8).ctypes.data,
            ctypes.byref(self._src_size),
            ctypes.byref(self._options),
        )
        if self._lib.LZ4F_isError(status):
            name = self._lib.LZ4F_getErrorName(status).decode(errors="replace")
            problem = f"LZ4 frame is corrupt (liblz4: {name})"
        elif status:
            problem = "LZ4 frame is incomplete, or holds more than its blocks allow"
        elif self._src_size.value != len(frame):
            problem = f"LZ4 frame is followed by {len(frame) - self._src_size.value} other bytes"
        else:
            return self._dst_size.value
        self._restart()
        raise ValueError(problem)

    def _new_context(self) -> ctypes.c_void_p:
        context = ctypes.c_void_p()
        status = self._lib.LZ4F_createDecompressionContext(ctypes.byref(context), _LZ4F_VERSION)
        if self._lib.LZ4F_isError(status):
            raise MemoryError("liblz4 could not create a decompression context")
        return context

    def _restart(self) -> None:
        """After a failed frame the context may hold its state: replace it."""
        self._finalizer()
        self._context = self._new_context()
        self._finalizer = weakref.finalize(self, self._free, self._lib, self._context)

    @staticmethod
    def _free(lib: ctypes.CDLL, context: ctypes.c_void_p) -> None:
        lib.LZ4F_freeDecompressionContext(context)
