"""Word producers for the emulated DAVIS: a packet source encoded lazily with faults, or a loop."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np

from davis_io.types import Packet, PacketSource
from davis_io.usb.encode import StreamEncoder
from davis_io.usb.layout import SensorLayout

__all__ = ["SourceWords", "StreamChunk", "StreamFaults", "looped_words"]


@dataclass(frozen=True)
class StreamFaults:
    """Faults the emulated device injects into its stream (all off by default).

    Attributes:
        device_start_us: device time of the source's first record; near 2**31 makes the stream
            cross a 31-bit wrap, and the jump there uses wrap words with multipliers > 1.
        reset_at_us: source times at which the device resets its timestamp (time restarts at 0).
        drop_event_windows_us: dropped transfers, as a DAVIS produces them: source-time windows
            ``[start, end)`` whose DVS events the device drops because the host did not take
            its transfers in time (MUX DROP_DVS_ON_TRANSFER_STALL); timestamps and frames
            survive, and the count goes to the MUX statistics registers 83/84.
        split_transfers: deliver transfers of awkward sizes so words split across transfers.
        stall_after_bytes: the bulk endpoint stalls once this many bytes were delivered.
        disconnect_after_bytes: the device disappears once this many bytes were delivered.
    """

    device_start_us: int = 0
    reset_at_us: tuple[int, ...] = ()
    drop_event_windows_us: tuple[tuple[int, int], ...] = ()
    split_transfers: bool = False
    stall_after_bytes: int | None = None
    disconnect_after_bytes: int | None = None


@dataclass(frozen=True)
class StreamChunk:
    """Words ready to stream, the stream time they reach and the DVS events the device dropped.

    Attributes:
        words: the 16-bit words.
        stream_time_us: time since the first record reached by the end of ``words`` (pacing).
        dropped_events: DVS events dropped by the device while producing ``words``.
    """

    words: np.ndarray
    stream_time_us: int
    dropped_events: int = 0


def _first_time(packet: Packet) -> int | None:
    times = [int(packet.events["t"][0])] if len(packet.events) else []
    times += [frame.readout_start_us for frame in packet.frames]
    times += [int(packet.imu["t"][0])] if len(packet.imu) else []
    times += [int(packet.triggers["t"][0])] if len(packet.triggers) else []
    return min(times) if times else None


def _without_windows(packet: Packet, windows) -> tuple[Packet, int]:
    if not windows or not len(packet.events):
        return packet, 0
    t = packet.events["t"]
    dropped = np.zeros(len(t), dtype=bool)
    for start, end in windows:
        dropped |= (t >= start) & (t < end)
    return replace(packet, events=packet.events[~dropped]), int(np.count_nonzero(dropped))


class SourceWords:
    """Iterator of chunks: ``source`` (entered here) encoded packet by packet, with faults.

    Device time 0 is the caller's own timestamp reset word that starts the stream; the source's
    first record lands at ``lead_us + faults.device_start_us``, leaving room for frames that
    started before it but arrive later. ``time_origin_us`` (source time at device time 0) is
    known once the first chunk was produced.
    """

    def __init__(
        self,
        source: PacketSource,
        layout: SensorLayout,
        faults: StreamFaults,
        *,
        adc_clock_mhz: float,
        accel_scale: int,
        gyro_scale: int,
        lead_us: int = 200_000,
    ):
        self.time_origin_us: int | None = None
        self._chunks = self._generate(
            source,
            layout,
            faults,
            lead_us,
            dict(adc_clock_mhz=adc_clock_mhz, accel_scale=accel_scale, gyro_scale=gyro_scale),
        )

    def __iter__(self) -> Iterator[StreamChunk]:
        return self

    def __next__(self) -> StreamChunk:
        return next(self._chunks)

    def _generate(self, source, layout, faults, lead_us, options) -> Iterator[StreamChunk]:
        with source:
            yield from self._encode(iter(source), layout, faults, lead_us, options)

    def _encode(self, packets, layout, faults, lead_us, options) -> Iterator[StreamChunk]:
        pending: list[Packet] = []
        first = None
        for packet in packets:
            pending.append(packet)
            first = _first_time(packet)
            if first is not None:
                break
        if first is None:
            return
        self.time_origin_us = first - lead_us - faults.device_start_us
        bounds = [first - lead_us, *sorted(faults.reset_at_us)]
        encoders = [
            StreamEncoder(
                layout,
                time_origin_us=self.time_origin_us if i == 0 else start,
                end_us=bounds[i + 1] if i + 1 < len(bounds) else None,
                **options,
            )
            for i, start in enumerate(bounds)
        ]
        yield from _segments(encoders, bounds, _chain(pending, packets), faults)


def _segments(encoders, bounds, packets, faults) -> Iterator[StreamChunk]:
    """Feed every packet to each segment's encoder; close a segment once time moved past it."""
    first = bounds[0]
    held: list[list[np.ndarray]] = [[] for _ in encoders]
    current, latest = 0, first
    for packet in packets:
        packet, dropped = _without_windows(packet, faults.drop_event_windows_us)
        latest = max(latest, _last_time(packet))
        for index in range(current, len(encoders)):
            held[index].append(encoders[index].push(_after(packet, bounds[index])))
        while current + 1 < len(encoders) and latest > bounds[current + 1] + encoders[0].hold_us:
            yield _close(encoders[current], held[current], bounds[current + 1], first)
            current += 1
        words = np.concatenate(held[current])
        held[current] = []
        yield StreamChunk(words, _stream_time(encoders[current], first), dropped)
    for index in range(current, len(encoders)):
        end = bounds[index + 1] if index + 1 < len(encoders) else None
        yield _close(encoders[index], held[index], end, first)


def _last_time(packet: Packet) -> int:
    times = [int(packet.events["t"][-1])] if len(packet.events) else []
    times += [frame.readout_end_us for frame in packet.frames]
    times += [int(packet.imu["t"][-1])] if len(packet.imu) else []
    times += [int(packet.triggers["t"][-1])] if len(packet.triggers) else []
    return max(times, default=-(2**62))


def _stream_time(encoder: StreamEncoder, first_us: int) -> int:
    return encoder.device_time_us + encoder.time_origin_us - first_us


def _chain(first: list[Packet], rest: Iterator[Packet]) -> Iterator[Packet]:
    yield from first
    yield from rest


def _after(packet: Packet, start_us: int) -> Packet:
    """Records at or after ``start_us`` (a frame belongs where its readout starts)."""
    return Packet(
        events=packet.events[packet.events["t"] >= start_us],
        frames=[frame for frame in packet.frames if frame.readout_start_us >= start_us],
        imu=packet.imu[packet.imu["t"] >= start_us],
        triggers=packet.triggers[packet.triggers["t"] >= start_us],
    )


def _close(
    encoder: StreamEncoder, held: list[np.ndarray], reset_us: int | None, first_us: int
) -> StreamChunk:
    parts = [*held, encoder.flush()]
    if reset_us is not None:
        parts.append(encoder.timestamp_reset_words(reset_us))
    return StreamChunk(np.concatenate(parts), _stream_time(encoder, first_us))


def looped_words(block: np.ndarray, block_us: int, repeats: int) -> Iterator[StreamChunk]:
    """Repeat a word block whose time span is a whole number of wraps (2**15 µs multiples).

    Timestamp words carry only the low 15 bits and wrap words are relative, so a block that
    starts and ends on a wrap boundary can be replayed back to back with time moving on.
    """
    for index in range(repeats):
        yield StreamChunk(block, (index + 1) * block_us)
