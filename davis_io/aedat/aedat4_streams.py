"""AEDAT 4.0 stream payloads (EVTS, FRME, IMUS, TRIG): FlatBuffer bytes to records and back.

Pure functions on uncompressed, size-prefixed FlatBuffers (davis-protocol.md §6.3). Events
decoded from a writable buffer are views of it (a reader decompresses every packet into a new
one); every other record is a copy.
"""

from __future__ import annotations

import numpy as np

from davis_io.aedat.flatbuf import (
    FlatBufferError,
    Scalar,
    TablesField,
    VectorField,
    build_buffer,
    root_table,
)
from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame

__all__ = [
    "FRAME_BIT_DEPTH_KEY",
    "RAW_EVENT_DTYPE",
    "STREAM_TYPES",
    "decode_events",
    "decode_frame",
    "decode_imu",
    "decode_triggers",
    "encode_events",
    "encode_frame",
    "encode_imu",
    "encode_triggers",
]

RAW_EVENT_DTYPE = np.dtype(
    {
        "names": ["t", "x", "y", "p"],
        "formats": ["<i8", "<i2", "<i2", "u1"],
        "offsets": [0, 8, 10, 12],
        "itemsize": 16,
    }
)
"""The 16-byte little-endian ``dv.Event`` struct: timestamp, x, y, polarity (1 = ON), padding.

:data:`~davis_io.types.EVENT_DTYPE` keeps the same offsets, so decoding is done in place."""

STREAM_TYPES = {
    "EVTS": ("events", "Array of events (polarity ON/OFF)."),
    "FRME": ("frames", "Standard frame (8-bit image)."),
    "IMUS": ("imu", "Inertial Measurement Unit data samples."),
    "TRIG": ("triggers", "External triggers and special signals."),
}
"""Stream type identifier: (output name, type description) as DV writes them in the infoNode."""

FRAME_BIT_DEPTH_KEY = "bitDepth"
"""infoNode attribute (frames stream ``info`` node) giving the significant bits of 16-bit frames."""

_OPENCV_DEPTHS = {0: np.uint8, 2: np.uint16}  # OpenCV depth code (type & 7) -> dtype


def decode_events(buf: bytes | np.ndarray) -> np.ndarray:
    """Decode an ``EVTS`` EventPacket into an :data:`EVENT_DTYPE` array.

    :data:`EVENT_DTYPE` has the file struct's layout, so the events are a view of ``buf`` when
    it is writable (a decompressed packet), else a copy; only the polarity byte changes, in
    place, from the file's boolean (any non-zero byte is ON) to -1/+1.
    """
    start, count = root_table(buf, b"EVTS").vector(0, RAW_EVENT_DTYPE.itemsize)
    events = np.frombuffer(buf, dtype=EVENT_DTYPE, count=count, offset=start)
    if not events.flags.writeable:
        events = events.copy()
    # Worked on a contiguous copy: numpy's loops over the 16-byte stride are 3x slower.
    polarity = events["p"].copy()
    np.not_equal(polarity, 0, out=polarity.view(np.bool_))
    polarity += polarity
    polarity -= 1
    events["p"] = polarity
    return events


def encode_events(events: np.ndarray) -> bytes:
    """Encode events as an ``EVTS`` EventPacket (polarity +1 becomes true)."""
    raw = np.zeros(len(events), dtype=RAW_EVENT_DTYPE)
    raw["t"] = events["t"]
    raw["x"] = events["x"]
    raw["y"] = events["y"]
    raw["p"] = events["p"] > 0
    return build_buffer(b"EVTS", [VectorField(0, raw.tobytes(), len(raw), align=8)])


def decode_frame(buf: bytes, bit_depth_16: int = 16) -> Frame:
    """Decode an ``FRME`` Frame table; absent fields take their schema defaults.

    Args:
        buf: the uncompressed FlatBuffer.
        bit_depth_16: significant bits of 16-bit images (``bitDepth`` attribute of the stream);
            16-bit pixels are stored left-aligned and shifted back by ``16 - bit_depth_16``.

    Returns:
        The frame: gray ``(H, W)`` or colour ``(H, W, C)`` in RGB(A) order; 8-bit images stay
        ``uint8`` with bit depth 8.

    Raises:
        FlatBufferError: unknown pixel format or a pixel vector of the wrong length.
    """
    table = root_table(buf, b"FRME")
    times = _frame_times(table)
    image_format = int(table.scalar(5, "<b", 0))
    width, height = int(table.scalar(6, "<h", 0)), int(table.scalar(7, "<h", 0))
    position = (int(table.scalar(8, "<h", 0)), int(table.scalar(9, "<h", 0)))
    dtype = _OPENCV_DEPTHS.get(image_format & 7)
    channels = (image_format >> 3) + 1
    if dtype is None or channels not in (1, 3, 4) or width < 0 or height < 0:
        raise FlatBufferError(
            f"frame format {image_format} ({width} x {height}) is not 8/16-bit with 1, 3 or 4 "
            "channels"
        )
    itemsize = np.dtype(dtype).itemsize
    start, count = table.vector(10, 1)
    expected = width * height * channels * itemsize
    if count != expected:
        raise FlatBufferError(f"frame has {count} pixel bytes, expected {expected}")
    pixels = np.frombuffer(
        buf, dtype=np.dtype(dtype).newbyteorder("<"), count=count // itemsize, offset=start
    ).astype(dtype)  # a copy: ``buf`` may be reused
    image = pixels.reshape((height, width, channels) if channels > 1 else (height, width))
    if channels > 1:  # stored BGR(A), ours RGB(A)
        image = image[..., [2, 1, 0, 3][:channels]].copy()
    bit_depth = 8
    if itemsize == 2:
        bit_depth = bit_depth_16
        image = image >> (16 - bit_depth_16)
    return Frame(image=image, bit_depth=bit_depth, position=position, **times)


def _frame_times(table) -> dict[str, int]:
    """The four frame times; absent ones are filled from ``timestamp`` and ``exposure``.

    dv-processing's writer leaves start/end of frame out (they read as 0) and stores the start
    of exposure in ``timestamp`` plus ``exposure``; DV 1.x files carry all five times.
    """
    timestamp, sof, eof, soe, eoe = (int(table.scalar(slot, "<q", 0)) for slot in range(5))
    if soe == 0 and eoe == 0:
        soe, eoe = timestamp, timestamp + int(table.scalar(11, "<q", 0))
    if sof == 0 and eof == 0:
        sof, eof = soe, eoe
    return {
        "exposure_start_us": soe,
        "exposure_end_us": eoe,
        "readout_start_us": sof,
        "readout_end_us": eof,
    }


def encode_frame(frame: Frame) -> bytes:
    """Encode a frame as an ``FRME`` table (8-bit as 8U, deeper images as left-aligned 16U).

    Like dv-processing's writer, slot 0 (``timestamp``) holds the start of exposure and slot 11
    the exposure in µs; slots 1-4 carry all four times.
    """
    image = frame.image
    channels = 1 if image.ndim == 2 else image.shape[2]
    if channels > 1:  # ours RGB(A), stored BGR(A)
        image = image[..., [2, 1, 0, 3][:channels]]
    if image.dtype == np.uint8:
        depth, pixels = 0, np.ascontiguousarray(image)
    else:
        depth = 2
        pixels = np.ascontiguousarray(image.astype("<u2") << (16 - frame.bit_depth))
    times = (
        frame.exposure_start_us,
        frame.readout_start_us,
        frame.readout_end_us,
        frame.exposure_start_us,
        frame.exposure_end_us,
    )
    fields = [Scalar(slot, "<q", value) for slot, value in enumerate(times)]
    fields += [
        Scalar(5, "<b", depth + 8 * (channels - 1)),
        Scalar(6, "<h", image.shape[1]),
        Scalar(7, "<h", image.shape[0]),
        Scalar(8, "<h", frame.position[0]),
        Scalar(9, "<h", frame.position[1]),
        VectorField(10, pixels.tobytes(), pixels.nbytes, align=1),
        Scalar(11, "<q", frame.exposure_us),
        Scalar(12, "<b", 1),  # FrameSource SENSOR
    ]
    return build_buffer(b"FRME", fields)


def decode_imu(buf: bytes) -> np.ndarray:
    """Decode an ``IMUS`` packet into an :data:`IMU_DTYPE` array (magnetometer dropped)."""
    tables = root_table(buf, b"IMUS").tables(0)
    imu = np.empty(len(tables), dtype=IMU_DTYPE)
    for index, table in enumerate(tables):
        values = [table.scalar(slot, "<f", 0.0) for slot in range(1, 8)]
        imu[index] = (table.scalar(0, "<q", 0), values[1:4], values[4:7], values[0])
    return imu


def encode_imu(imu: np.ndarray) -> bytes:
    """Encode IMU samples as an ``IMUS`` packet (magnetometer written as 0)."""
    tables = []
    for sample in imu:
        values = [sample["temperature_c"], *sample["acc_g"], *sample["gyro_dps"], 0.0, 0.0, 0.0]
        fields = [Scalar(0, "<q", int(sample["t"]))]
        fields += [Scalar(slot, "<f", float(v)) for slot, v in enumerate(values, start=1)]
        tables.append(fields)
    return build_buffer(b"IMUS", [TablesField(0, tables)])


def decode_triggers(buf: bytes) -> np.ndarray:
    """Decode a ``TRIG`` packet into a :data:`TRIGGER_DTYPE` array."""
    tables = root_table(buf, b"TRIG").tables(0)
    triggers = np.empty(len(tables), dtype=TRIGGER_DTYPE)
    for index, table in enumerate(tables):
        triggers[index] = (table.scalar(0, "<q", 0), table.scalar(1, "<b", 0))
    return triggers


def encode_triggers(triggers: np.ndarray) -> bytes:
    """Encode triggers as a ``TRIG`` packet."""
    tables = [[Scalar(0, "<q", int(t["t"])), Scalar(1, "<b", int(t["kind"]))] for t in triggers]
    return build_buffer(b"TRIG", [TablesField(0, tables)])
