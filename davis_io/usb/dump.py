"""Raw bulk-IN byte dumps: decode one as a packet source, or write one from any packet source."""

from __future__ import annotations

from pathlib import Path
from types import TracebackType
from typing import BinaryIO, Self

import numpy as np

from davis_io.errors import FormatError, UsageError
from davis_io.types import ColorFilter, PacketSource, SourceInfo
from davis_io.usb.emulated_stream import SourceWords, StreamFaults
from davis_io.usb.layout import SensorLayout
from davis_io.usb.protocol import Special
from davis_io.usb.words import WordDecoder

__all__ = ["MODELS", "RawUsbDump", "open_raw_usb_dump", "write_raw_usb_dump"]

MODELS = {
    "davis346": SensorLayout(),
    "davis240": SensorLayout(
        dvs_columns=240, dvs_rows=180, aps_columns=240, aps_rows=180, adc_doubling=True
    ),
}
"""Sensor layout of each model name accepted by ``--raw-usb``."""

_READ_BYTES = 1 << 20


def _layout(model: str) -> SensorLayout:
    try:
        return MODELS[model.lower()]
    except KeyError:
        raise UsageError(
            f"unknown camera model {model!r} for a raw USB dump; use one of {', '.join(MODELS)}"
        ) from None


class RawUsbDump:
    """A file of bulk-IN bytes as a packet source (one packet per MiB read).

    Times are the device clock of the dump (µs since its first timestamp reset).
    """

    def __init__(self, path: str | Path, model: str, color_filter: ColorFilter = ColorFilter.MONO):
        self.path = Path(path)
        self.layout = _layout(model)
        self.info = SourceInfo(
            camera=model.upper(),
            serial="",
            width=self.layout.width,
            height=self.layout.height,
            color_filter=color_filter,
            origin=f"replay:{self.path.name}",
            extra={"format": "raw USB bulk-IN dump"},
        )
        self.decoder = WordDecoder(self.layout)
        self._file: BinaryIO | None = None

    def __enter__(self) -> Self:
        try:
            self._file = self.path.open("rb")
        except OSError as error:
            raise FormatError(
                f"cannot open raw USB dump: {error.strerror}", path=str(self.path)
            ) from error
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __iter__(self):
        if self._file is None:
            raise UsageError("use the raw USB dump inside a `with` block before iterating it")
        while chunk := self._file.read(_READ_BYTES):
            yield self.decoder.decode(chunk)
        tail = self.decoder.finish()
        if tail.notes:
            yield tail


def open_raw_usb_dump(path: str | Path, model: str) -> PacketSource:
    """Open a raw bulk-IN byte dump of a ``model`` camera (``"davis346"`` or ``"davis240"``)."""
    return RawUsbDump(path, model)


def write_raw_usb_dump(
    source: PacketSource, path: str | Path, *, model: str = "davis346", adc_clock_mhz: float = 30.0
) -> int:
    """Encode every packet of ``source`` as a DAVIS would send it; return the bytes written.

    The dump starts with a timestamp reset (device time 0), 200 ms before the source's first
    record, so frames that started before it still fit.
    """
    layout = _layout(model)
    written = 0
    with Path(path).open("wb") as file:
        reset = np.array([Special.TIMESTAMP_RESET], "<u2").tobytes()
        file.write(reset)
        written += len(reset)
        for chunk in SourceWords(
            source, layout, StreamFaults(), adc_clock_mhz=adc_clock_mhz, accel_scale=1, gyro_scale=1
        ):
            data = chunk.words.astype("<u2", copy=False).tobytes()
            file.write(data)
            written += len(data)
    return written
