"""A session as a packet stream again (what an export to a recording format reads)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from davis_io.session.store import Session
from davis_io.types import Packet, SourceInfo

__all__ = ["DAVIS_BIT_DEPTH", "session_packets", "session_source_info"]

_CHUNK_EVENTS = 1 << 20
DAVIS_BIT_DEPTH = 10
"""ADC bits of a DAVIS frame."""


def session_source_info(session: Session) -> SourceInfo:
    """The camera facts of a session as a :class:`SourceInfo`."""
    manifest = session.manifest
    return SourceInfo(
        camera=manifest.camera,
        serial=manifest.serial,
        width=manifest.width,
        height=manifest.height,
        color_filter=session.color_filter,
        origin=manifest.source,
        firmware_version=manifest.firmware_version,
        logic_version=manifest.logic_version,
        extra=dict(manifest.device_config),
    )


def session_packets(session: Session, *, chunk_events: int = _CHUNK_EVENTS) -> Iterator[Packet]:
    """Replay a session as packets in time order, as a camera would have delivered them.

    Each packet holds up to ``chunk_events`` events, plus the frames whose readout ended, and the
    IMU samples and triggers that came, no later than its last event (everything left goes with
    the last packet).
    """
    table = session.frames_table()
    imu, triggers = session.imu(), session.triggers()
    total = session.event_count
    next_frame = next_imu = next_trigger = 0
    for first in range(0, max(total, 1), chunk_events):
        events = session.events_by_index(first, first + chunk_events)
        last_chunk = first + chunk_events >= total
        horizon = np.iinfo(np.int64).max if last_chunk else int(events["t"][-1])
        frame_stop = int(np.searchsorted(table.readout_end_us, horizon, side="right"))
        imu_stop = int(np.searchsorted(imu["t"], horizon, side="right"))
        trigger_stop = int(np.searchsorted(triggers["t"], horizon, side="right"))
        yield Packet(
            events=events,
            frames=[session.frame(index) for index in range(next_frame, frame_stop)],
            imu=imu[next_imu:imu_stop],
            triggers=triggers[next_trigger:trigger_stop],
        )
        next_frame, next_imu, next_trigger = frame_stop, imu_stop, trigger_stop
