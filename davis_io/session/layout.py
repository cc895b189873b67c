"""The ``session.h5`` layout: paths, dtypes, chunks, appends and reads for writer and reader."""

from __future__ import annotations

from collections.abc import Mapping

import h5py
import numpy as np

from davis_io.bins import ExposureBins
from davis_io.types import EVENT_DTYPE

__all__ = [
    "EVENT_FIELDS",
    "FRAME_TIMES",
    "FILE_FORMAT",
    "H5_NAME",
    "append_rows",
    "bins_path",
    "complete_rows",
    "PORTABLE",
    "create_bins_group",
    "dataset_filters",
    "create_image_dataset",
    "create_layout",
    "poses_path",
    "read_events_between",
    "search_sorted_dataset",
    "write_bins_row",
]

H5_NAME = "session.h5"
FILE_FORMAT = ("v110", "v110")
"""HDF5 file-format versions ``session.h5`` is written in (h5py's ``libver``): those of HDF5
1.10, the first with single-writer/multiple-reader mode, so that any HDF5 from 1.10 on reads
it. ("latest" would be the format of the HDF5 that h5py bundles, 2.0, which no 1.x tool opens:
h5dump 1.10.8 failed on every dataset.)"""
EVENT_FIELDS = ("t", "x", "y", "p")
FRAME_TIMES = ("exposure_start_us", "exposure_end_us", "readout_start_us", "readout_end_us")
_EVENT_CHUNK = 1 << 17
_SMALL_CHUNK = 1024
_FAST = {"compression": "lzf", "shuffle": True}
"""LZF with byte shuffle: fast enough for a live stream, 20x smaller times, 2x smaller counts."""
PORTABLE = {"compression": "gzip", "compression_opts": 1, "shuffle": True}
"""Deflate (level 1) with byte shuffle, for what is written after the recording: every HDF5
build reads it (HDFView, MATLAB, h5dump with no plug-in), and nothing there races a stream."""
_PACKED = {"scaleoffset": 0}
"""HDF5's integer scale-offset filter (lossless for integers with automatic bit width): each
chunk stores value - minimum in as many bits as its range needs."""
_EVENT_COMPRESSION = {"t": _FAST, "x": {}, "y": {}, "p": _PACKED}
"""Per event column, what a 12 M events/s live stream can afford on a busy 2-core machine:
times (monotonic) 8 -> ~0.4 bytes with LZF + shuffle (18 ms of CPU per million events),
polarity 1 -> 0.25 bytes bit-packed (4 ms). x and y stay plain (2 bytes each): bit-packing
them (-> ~1.1 bytes) costs another 14 ms per million events, which measurably caused drops
at 12 M events/s when the machine was shared (tools/bench_record.py)."""


def bins_path(b: int) -> str:
    """Group path of the bins for ``b`` bins per exposure."""
    return f"/bins/b{int(b)}"


def poses_path(b: int) -> str:
    """Group path of the poses of the ``b + 1`` latent time points per frame."""
    return f"/poses/b{int(b)}"


def _growable(
    group: h5py.Group, name: str, dtype, row_shape=(), chunk_rows=_SMALL_CHUNK, compression=None
):
    """Create an empty chunked dataset that grows along its first axis (LZF unless told)."""
    return group.create_dataset(
        name,
        shape=(0, *row_shape),
        maxshape=(None, *row_shape),
        dtype=dtype,
        chunks=(chunk_rows, *row_shape),
        **(_FAST if compression is None else compression),
    )


def create_layout(h5: h5py.File, *, width: int, height: int, b: int) -> None:
    """Create every dataset of a new session (all empty) except ``/frames/image``.

    The image dataset waits for the first frame, whose dtype it takes
    (:func:`create_image_dataset`); the bins for ``b`` are created here.
    """
    events = h5.create_group("events")
    for name, dtype in (("t", np.int64), ("x", np.uint16), ("y", np.uint16), ("p", np.int8)):
        compression = _EVENT_COMPRESSION[name]
        _growable(events, name, dtype, chunk_rows=_EVENT_CHUNK, compression=compression)
    frames = h5.create_group("frames")
    for name in FRAME_TIMES:
        _growable(frames, name, np.int64)
    _growable(frames, "events_lost", np.bool_)
    imu = h5.create_group("imu")
    _growable(imu, "t", np.int64)
    _growable(imu, "acc_g", np.float32, (3,))
    _growable(imu, "gyro_dps", np.float32, (3,))
    _growable(imu, "temperature_c", np.float32)
    triggers = h5.create_group("triggers")
    _growable(triggers, "t", np.int64)
    _growable(triggers, "kind", np.int8)
    create_bins_group(h5, b=b, width=width, height=height)


def create_image_dataset(
    h5: h5py.File, *, width: int, height: int, image_dtype, bit_depth: int
) -> h5py.Dataset:
    """Create ``/frames/image`` with the attribute ``bit_depth`` (significant ADC bits)."""
    frames = h5.require_group("frames")
    image = _growable(frames, "image", np.dtype(image_dtype), (height, width), chunk_rows=1)
    image.attrs["bit_depth"] = int(bit_depth)
    return image


def create_bins_group(
    h5: h5py.File, *, b: int, width: int, height: int, live: bool = True
) -> h5py.Group:
    """Create the empty datasets of ``/bins/b{b}`` (LZF while recording, else :data:`PORTABLE`)."""
    group = h5.require_group(bins_path(b))
    compression = None if live else PORTABLE
    for name, dtype, row, rows in (
        ("split_us", np.int64, (b + 1,), _SMALL_CHUNK),
        ("weights", np.float64, (b + 1,), _SMALL_CHUNK),
        ("raw", np.int16, (b, height, width), 1),
        ("calibrated", np.float32, (b, height, width), 1),
        ("event_count", np.int64, (), _SMALL_CHUNK),
    ):
        _growable(group, name, dtype, row, chunk_rows=rows, compression=compression)
    return group


def dataset_filters(h5: h5py.File) -> dict[str, list[str]]:
    """Each compression filter the file uses and the datasets that use it (``none``: plain)."""
    found: dict[str, list[str]] = {}

    def visit(name: str, item) -> None:
        if isinstance(item, h5py.Dataset):
            kind = item.compression or ("scaleoffset" if item.scaleoffset is not None else "none")
            found.setdefault(kind, []).append(name)

    h5.visititems(visit)
    return found


def append_rows(dataset: h5py.Dataset, rows: np.ndarray) -> None:
    """Append ``rows`` along the first axis of a growable dataset."""
    if len(rows) == 0:
        return
    start = dataset.shape[0]
    dataset.resize(start + len(rows), axis=0)
    dataset[start:] = rows


def write_bins_row(group: Mapping[str, h5py.Dataset], bins: ExposureBins) -> None:
    """Append one frame's bins to a ``/bins/b{b}`` group or its datasets (``event_count`` last)."""
    append_rows(group["split_us"], bins.split_us[None])
    append_rows(group["weights"], bins.weights[None])
    append_rows(group["raw"], bins.raw[None])
    append_rows(group["calibrated"], bins.calibrated[None])
    append_rows(group["event_count"], np.array([bins.event_count], dtype=np.int64))


def complete_rows(group: h5py.Group | None, names) -> int:
    """Rows present in every named dataset of ``group`` (a crash may leave some one row longer).

    A missing group (a recorder killed before its first frame) has no rows.
    """
    if group is None:
        return 0
    return min((group[name].shape[0] if name in group else 0 for name in names), default=0)


def search_sorted_dataset(times: h5py.Dataset, stored: int, value_us: int, side: str) -> int:
    """``np.searchsorted`` over the first ``stored`` rows of a sorted on-disk dataset.

    Bisects by reading single values until one chunk remains, then searches that chunk.
    """
    low, high = 0, stored
    chunk = times.chunks[0] if times.chunks else 1 << 16
    while high - low > chunk:
        middle = (low + high) // 2
        probe = int(times[middle])
        if probe < value_us or (side == "right" and probe == value_us):
            low = middle + 1
        else:
            high = middle
    return low + int(np.searchsorted(times[low:high], value_us, side=side))


def read_events_between(events: h5py.Group, stored: int, t0_us: int, t1_us: int) -> np.ndarray:
    """Events of ``/events`` with ``t0_us <= t <= t1_us`` among the first ``stored`` rows."""
    first = search_sorted_dataset(events["t"], stored, t0_us, "left")
    stop = search_sorted_dataset(events["t"], stored, t1_us, "right")
    out = np.empty(max(stop - first, 0), dtype=EVENT_DTYPE)
    for name in EVENT_FIELDS:
        out[name] = events[name][first : first + len(out)]
    return out
