"""Colour frames as a DAVIS gives them: demosaiced RGB in a file back to its raw mosaic.

DV records a colour DAVIS's frames demosaiced (3 channels); a session stores raw frames, the
sensor's mosaic, as the camera read them. Every site's own sample survives bilinear
demosaicing, so taking each pixel's filter channel gives the mosaic back exactly. A file that
states no colour filter and whose channels are all alike (a grey frame saved as colour by a
converter) holds a mono sensor's frames: one channel is the frame.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

from davis_io.colorfilter import mosaic_of
from davis_io.errors import FormatError
from davis_io.types import ColorFilter, Frame, Packet, PacketSource

__all__ = ["RawMosaicFrames"]


class RawMosaicFrames:
    """A replay whose 3-channel frames come out as the raw mosaic of ``color_filter``.

    Args:
        source: the file's packet source, not yet entered.
        color_filter: the sensor's pattern (``--color-filter``), or None for the one the file
            states; the session records it.
    """

    def __init__(self, source: PacketSource, color_filter: ColorFilter | None):
        self._source = source
        stated = source.info.color_filter
        self.color_filter = color_filter or stated
        self.info = dataclasses.replace(source.info, color_filter=self.color_filter)

    def __enter__(self) -> RawMosaicFrames:
        self._source.__enter__()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self._source.__exit__(exc_type, exc, tb)

    def __iter__(self) -> Iterator[Packet]:
        for packet in self._source:
            if any(frame.image.ndim == 3 for frame in packet.frames):
                packet.frames = [self._raw(frame) for frame in packet.frames]
            yield packet

    def _raw(self, frame: Frame) -> Frame:
        if frame.image.ndim == 2:
            return frame
        if not self.color_filter.is_color:
            if (frame.image[..., 1:3] == frame.image[..., :1]).all():  # grey (alpha aside)
                return dataclasses.replace(frame, image=frame.image[..., 0].copy())
            raise FormatError(
                f"the frame exposed from t={frame.exposure_start_us} µs has "
                f"{frame.image.shape[2]} channels (demosaiced colour) and the file states no "
                "colour filter: give the sensor's with --color-filter (a colour DAVIS346 is RGGB)",
                path=str(getattr(self._source, "path", self.info.origin)),
            )
        return dataclasses.replace(frame, image=mosaic_of(frame.image, self.color_filter))
