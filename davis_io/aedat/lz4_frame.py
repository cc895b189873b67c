"""LZ4 frame decompression block by block, with ``lz4.frame`` for every unusual frame.

An AEDAT 4.0 packet payload is one LZ4 frame (LZ4 Frame Format Description, version 1.6):

* magic number ``04 22 4D 18``;
* frame descriptor: FLG (version ``01`` in bits 7-6, block independence bit 5, block checksum
  bit 4, content size bit 3, content checksum bit 2, reserved bit 1, dictionary id bit 0), BD
  (block maximum size code 4-7 in bits 6-4 = 64 KiB, 256 KiB, 1 MiB, 4 MiB; other bits
  reserved), the optional 8-byte content size, the optional 4-byte dictionary id, and HC, the
  second byte of the XXH32 of the descriptor from FLG on;
* data blocks: a little-endian 32-bit size whose top bit marks an uncompressed block, the
  block bytes, and a 4-byte block checksum if flagged; a size of 0 is the end mark;
* a 4-byte content checksum if flagged.

The frames DV and our writer produce (linked 64 KiB blocks, no checksums, no content size) are
laid out here, which bounds their output by the block count, and decoded into a new array of
that size: by the system's liblz4 in one call when it has one (:mod:`davis_io.aedat.liblz4`),
otherwise block by block with ``lz4.block``, each compressed block being one LZ4 block whose
matches may reach up to 64 KiB back into the output of the blocks before it (linked mode), so
that tail is passed as the block's dictionary, and an uncompressed block copied as it is. Either
way the caller owns the array: an AEDAT 4.0 reader hands out its events as a view of it, with no
copy (``lz4.frame.decompress`` would allocate a context and bytes of its own for every frame,
and the events would still have to be copied out of them).

Frames this module does not lay out go to ``lz4.frame.decompress`` unchanged, so they are
decoded, or rejected with its error, exactly as before: checksummed blocks or content (their
XXH32 over the whole data is not available without ``lz4.frame``), a dictionary id, reserved or
unknown bits, a header checksum mismatch, a block size beyond the maximum or the data, a missing
end mark, or bytes after the frame.
"""

from __future__ import annotations

import functools
import struct
from typing import NamedTuple

import lz4.block
import lz4.frame
import numpy as np

from davis_io.aedat.liblz4 import NativeFrameDecoder, system_liblz4

__all__ = [
    "FrameDecompressor",
    "FrameLayout",
    "decompress_frame",
    "frame_layout",
    "header_checksum",
]

MAGIC = b"\x04\x22\x4d\x18"
WINDOW = 64 * 1024
"""How far back an LZ4 match may reach: the dictionary size of a linked block."""

_BLOCK_MAX = {4: 64 * 1024, 5: 256 * 1024, 6: 1024 * 1024, 7: 4 * 1024 * 1024}
_FLG_VERSION = 0b0100_0000
_FLG_INDEPENDENT = 0b0010_0000
_FLG_CONTENT_SIZE = 0b0000_1000
_FLG_HANDLED_ELSEWHERE = 0b0001_0111  # block checksum, content checksum, reserved, dictionary id
_BD_RESERVED = 0b1000_1111
_UNCOMPRESSED = 0x8000_0000
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")


class FrameLayout(NamedTuple):
    """Where a frame's blocks lie: ``blocks`` is ``[(start, size, compressed), ...]``."""

    linked: bool
    block_max: int
    content_size: int | None
    blocks: list[tuple[int, int, bool]]

    @property
    def capacity(self) -> int:
        """Most bytes the blocks can hold: a compressed block at most ``block_max``."""
        return sum(self.block_max if compressed else size for _, size, compressed in self.blocks)


class FrameDecompressor:
    """Decompresses LZ4 frames, each into a new writable array that the caller keeps.

    Uses the system's liblz4 when there is one (``native=None`` or ``True``), else python-lz4.
    """

    def __init__(self, native: bool | None = None):
        """Pick the decoder.

        Args:
            native: True to require liblz4, False to use python-lz4, None for liblz4 when the
                system has it.

        Raises:
            RuntimeError: ``native`` is True and the system has no usable liblz4.
        """
        lib = system_liblz4() if native is not False else None
        if native and lib is None:
            raise RuntimeError("no usable liblz4 (1.8 or later) on this system")
        self._native = NativeFrameDecoder(lib) if lib is not None else None

    @property
    def native(self) -> bool:
        """True when frames are decoded by the system's liblz4."""
        return self._native is not None

    def decompress(self, data: bytes | memoryview) -> np.ndarray:
        """Decompress one complete LZ4 frame into a new uint8 array.

        Raises:
            RuntimeError: ``lz4.frame`` rejects a frame it decodes (see the module docstring).
            ValueError: a block does not decompress, or the output disagrees with the content
                size.
        """
        layout = frame_layout(data)
        if layout is None:
            return np.frombuffer(bytearray(lz4.frame.decompress(data)), np.uint8)
        out = np.empty(layout.capacity, np.uint8)
        if self._native is not None:
            size = self._native.decode_into(data, out)
        else:
            size = _decode_blocks(data, layout, out)
        if layout.content_size is not None and size != layout.content_size:
            raise ValueError(f"LZ4 frame holds {size} bytes, its header says {layout.content_size}")
        return out[:size]


def _decode_blocks(data: bytes, layout: FrameLayout, out: np.ndarray) -> int:
    """Decode the frame's blocks one by one with python-lz4; return the bytes written."""
    view, written, pos = memoryview(data), memoryview(out), 0
    for start, size, compressed in layout.blocks:
        block = view[start : start + size]
        if compressed:
            window = written[max(0, pos - WINDOW) : pos] if layout.linked else b""
            try:
                block = lz4.block.decompress(block, uncompressed_size=layout.block_max, dict=window)
            except lz4.block.LZ4BlockError as error:
                raise ValueError(
                    f"LZ4 block at frame byte {start - 4} is corrupt ({error})"
                ) from None
        written[pos : pos + len(block)] = block
        pos += len(block)
    return pos


def decompress_frame(data: bytes) -> bytes:
    """Decompress one complete LZ4 frame into new bytes (errors as in FrameDecompressor)."""
    return FrameDecompressor().decompress(data).tobytes()


def frame_layout(data: bytes) -> FrameLayout | None:
    """Parse the frame descriptor and block sizes, or return None for ``lz4.frame`` to decode."""
    if len(data) < 7 or data[:4] != MAGIC:
        return None
    flg, bd = data[4], data[5]
    block_max = _BLOCK_MAX.get(bd >> 4 & 7)
    if (
        flg & 0b1100_0000 != _FLG_VERSION
        or flg & _FLG_HANDLED_ELSEWHERE
        or bd & _BD_RESERVED
        or block_max is None
    ):
        return None
    pos, content_size = 6, None
    if flg & _FLG_CONTENT_SIZE:
        if len(data) < 15:
            return None
        content_size, pos = _U64.unpack_from(data, 6)[0], 14
    if data[pos] != header_checksum(bytes(data[4:pos])):
        return None
    pos, blocks = pos + 1, []
    while pos + 4 <= len(data):
        word = _U32.unpack_from(data, pos)[0]
        pos += 4
        if word == 0:
            break
        size = word & ~_UNCOMPRESSED
        if size > block_max or pos + size > len(data):
            return None
        blocks.append((pos, size, not word & _UNCOMPRESSED))
        pos += size
    else:
        return None  # no end mark
    if pos != len(data):
        return None
    return FrameLayout(not flg & _FLG_INDEPENDENT, block_max, content_size, blocks)


@functools.lru_cache(maxsize=64)
def header_checksum(descriptor: bytes) -> int:
    """HC: ``(XXH32(descriptor, seed 0) >> 8) & 0xFF`` for a descriptor of at most 15 bytes.

    XXH32 of an input shorter than 16 bytes: start from ``PRIME5 + length``, fold in each 4-byte
    word and then each remaining byte, and finish with the avalanche. A file's packets share
    one descriptor, hence the cache.
    """
    if len(descriptor) >= 16:
        raise ValueError("an LZ4 frame descriptor has at most 15 bytes")
    h = (_PRIME5 + len(descriptor)) & _MASK
    words_end = len(descriptor) // 4 * 4
    for pos in range(0, words_end, 4):
        h = (h + _U32.unpack_from(descriptor, pos)[0] * _PRIME3) & _MASK
        h = (_rotl(h, 17) * _PRIME4) & _MASK
    for byte in descriptor[words_end:]:
        h = (h + byte * _PRIME5) & _MASK
        h = (_rotl(h, 11) * _PRIME1) & _MASK
    h = ((h ^ (h >> 15)) * _PRIME2) & _MASK
    h = ((h ^ (h >> 13)) * _PRIME3) & _MASK
    h ^= h >> 16
    return (h >> 8) & 0xFF


_PRIME1, _PRIME2, _PRIME3, _PRIME4, _PRIME5 = (
    0x9E3779B1,
    0x85EBCA77,
    0xC2B2AE3D,
    0x27D4EB2F,
    0x165667B1,
)
_MASK = 0xFFFF_FFFF


def _rotl(value: int, bits: int) -> int:
    return ((value << bits) | (value >> (32 - bits))) & _MASK
