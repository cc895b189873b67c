"""AEDAT 4.0 writer for any packet stream: events, frames, IMU, triggers and the data table."""

from __future__ import annotations

import struct
from collections.abc import Iterable
from pathlib import Path
from typing import BinaryIO

import numpy as np

from davis_io.aedat.aedat4_header import (
    MAGIC,
    Compression,
    DataTableEntry,
    IOHeader,
    StreamDescription,
    build_data_table,
    build_info_node,
    build_io_header,
    compress,
)
from davis_io.aedat.aedat4_streams import (
    FRAME_BIT_DEPTH_KEY,
    encode_events,
    encode_frame,
    encode_imu,
    encode_triggers,
)
from davis_io.colorfilter import DEVICE_COLOR_FILTERS
from davis_io.errors import UsageError
from davis_io.types import Closing, Frame, Packet, SourceInfo

__all__ = ["Aedat4Writer", "write_aedat4"]

EVENTS_PER_FILE_PACKET = 1 << 17
"""Largest number of events written into one file packet (bigger arrays are split)."""

_STREAM_IDS = {"EVTS": 0, "FRME": 1, "IMUS": 2, "TRIG": 3}
_TABLE_PLACEHOLDER = -2  # replaced at close by the real data table position (same size)


class Aedat4Writer(Closing):
    """Write packets to an AEDAT 4.0 file that DV tools and dv-processing open.

    Use as a context manager; the data table is written and the header patched on exit (also
    when an exception ends the ``with`` block, so everything written stays readable).

    Frames deeper than 8 bits are stored as 16-bit gray/colour (OpenCV 16U), left-aligned like
    DV's 16-bit normalized images, and the frames stream's ``info`` node records ``bitDepth``
    so that :class:`Aedat4Reader` gives back exactly the values written.
    """

    def __init__(
        self,
        path: str | Path,
        info: SourceInfo,
        compression: Compression = Compression.LZ4,
        frame_bit_depth: int = 10,
    ):
        """Create ``path`` and write its header.

        Args:
            path: the file to create (overwritten if it exists).
            info: camera name, serial and resolution for the infoNode.
            compression: packet codec.
            frame_bit_depth: significant bits of 16-bit frames (DAVIS ADC: 10).
        """
        if not 9 <= frame_bit_depth <= 16:
            raise UsageError(
                f"frame_bit_depth must be 9..16 for 16-bit frames, not {frame_bit_depth}"
            )
        self.path = Path(path)
        self.compression = Compression(compression)
        self.frame_bit_depth = frame_bit_depth
        self._entries: list[DataTableEntry] = []
        source = f"{info.camera}_{info.serial}" if info.serial else info.camera
        size = (info.width, info.height)
        frames_info = {FRAME_BIT_DEPTH_KEY: frame_bit_depth}
        if info.color_filter.is_color:  # as a DAVIS states it: the APS register value
            frames_info["colorFilter"] = DEVICE_COLOR_FILTERS.index(info.color_filter)
        self._info_node = build_info_node(
            [
                StreamDescription(0, "EVTS", "events", *size, source),
                StreamDescription(1, "FRME", "frames", *size, source, frames_info),
                StreamDescription(2, "IMUS", "imu", source=source),
                StreamDescription(3, "TRIG", "triggers", source=source),
            ],
            self.compression,
        )
        self._file: BinaryIO = self.path.open("wb")
        self._file.write(MAGIC + self._header(_TABLE_PLACEHOLDER))

    def write(self, packet: Packet) -> None:
        """Append every record of ``packet`` (one file packet per kind, one per frame)."""
        for start in range(0, len(packet.events), EVENTS_PER_FILE_PACKET):
            chunk = packet.events[start : start + EVENTS_PER_FILE_PACKET]
            self._write_packet("EVTS", encode_events(chunk), chunk["t"])
        for frame in packet.frames:
            self._check_frame(frame)
            start = np.array([frame.exposure_start_us])
            self._write_packet("FRME", encode_frame(frame), start)
        if len(packet.imu):
            self._write_packet("IMUS", encode_imu(packet.imu), packet.imu["t"])
        if len(packet.triggers):
            self._write_packet("TRIG", encode_triggers(packet.triggers), packet.triggers["t"])

    def close(self) -> None:
        """Write the data table, patch the header with its position and close the file."""
        if self._file.closed:
            return
        position = self._file.tell()
        self._file.write(compress(self.compression, build_data_table(self._entries)))
        self._file.seek(len(MAGIC))
        self._file.write(self._header(position))
        self._file.close()

    def _header(self, table_position: int) -> bytes:
        return build_io_header(IOHeader(self.compression, table_position, self._info_node))

    def _check_frame(self, frame: Frame) -> None:
        if frame.image.dtype not in (np.uint8, np.uint16):
            raise UsageError(f"frame images must be uint8 or uint16, not {frame.image.dtype}")
        if frame.image.dtype == np.uint16 and frame.bit_depth != self.frame_bit_depth:
            raise UsageError(
                f"frame has bit depth {frame.bit_depth} but the writer was opened with "
                f"frame_bit_depth={self.frame_bit_depth}; open it with the frames' depth"
            )

    def _write_packet(self, type_id: str, flatbuffer: bytes, times: np.ndarray) -> None:
        payload = compress(self.compression, flatbuffer)
        stream_id = _STREAM_IDS[type_id]
        self._file.write(struct.pack("<ii", stream_id, len(payload)))
        self._entries.append(
            DataTableEntry(
                self._file.tell(),
                stream_id,
                len(payload),
                len(times),
                int(times.min()),
                int(times.max()),
            )
        )
        self._file.write(payload)


def write_aedat4(
    packets: Iterable[Packet],
    path: str | Path,
    info: SourceInfo | None = None,
    compression: Compression = Compression.LZ4,
    frame_bit_depth: int = 10,
) -> Path:
    """Write every packet of a source (or any iterable of packets) to an AEDAT 4.0 file.

    Args:
        packets: a PacketSource (its ``info`` is used when ``info`` is None) or packets.
        path: the file to create.
        info: camera facts; required when ``packets`` has no ``info``.
        compression: packet codec.
        frame_bit_depth: significant bits of 16-bit frames.

    Returns:
        The path written.
    """
    info = info or getattr(packets, "info", None)
    if info is None:
        raise UsageError("write_aedat4 needs `info` (camera and resolution) for plain packets")
    with Aedat4Writer(path, info, compression, frame_bit_depth) as writer:
        for packet in packets:
            writer.write(packet)
    return Path(path)
