"""Summary of any packet source: counts, times, rates, frames, IMU, triggers, gaps."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from davis_io.types import PacketSource, TriggerKind

__all__ = ["DEFAULT_GAP_US", "RecordingSummary", "StreamStats", "format_summary", "summarize"]

DEFAULT_GAP_US = 100_000
"""An event-free stretch at least this long (µs) is reported as a gap."""


@dataclass
class StreamStats:
    """Count, first/last time and order checks of one record stream (times in µs)."""

    count: int = 0
    first_us: int | None = None
    last_us: int | None = None
    non_monotonic: int = 0

    def add(self, times: np.ndarray) -> None:
        """Take the next time-ordered batch of timestamps into account."""
        if len(times) == 0:
            return
        previous = times[:1] if self.last_us is None else np.array([self.last_us])
        self.non_monotonic += int(np.count_nonzero(np.diff(times, prepend=previous) < 0))
        self.first_us = int(times[0]) if self.first_us is None else self.first_us
        self.last_us = int(times[-1])
        self.count += len(times)

    @property
    def duration_us(self) -> int:
        """Last minus first time, 0 when empty."""
        return 0 if self.first_us is None else self.last_us - self.first_us


@dataclass
class RecordingSummary:
    """What ``seecap inspect`` reports about a recording or live source.

    Times are µs on the source's clock; ``*_range`` are inclusive ``[min, max]`` or None.
    """

    format: str
    camera: str
    serial: str
    width: int
    height: int
    origin: str
    streams: list[str]
    packets: int = 0
    event_packets: int = 0
    events: StreamStats = field(default_factory=StreamStats)
    on_events: int = 0
    x_range: list[int] | None = None
    y_range: list[int] | None = None
    gaps: list[list[int]] = field(default_factory=list)
    frames: StreamStats = field(default_factory=StreamStats)
    frame_shapes: list[str] = field(default_factory=list)
    frame_exposure_starts_us: list[int] = field(default_factory=list)
    frame_exposures_us: list[int] = field(default_factory=list)
    frame_readouts_us: list[int] = field(default_factory=list)
    imu: StreamStats = field(default_factory=StreamStats)
    imu_temperature_sum_c: float = 0.0
    triggers: StreamStats = field(default_factory=StreamStats)
    trigger_kinds: dict[str, int] = field(default_factory=dict)
    dropped_events: int = 0
    notes: list[str] = field(default_factory=list)
    time_range_us: list[int] | None = None

    @property
    def event_rate_hz(self) -> float:
        """Events per second over the event time span (0 when it is empty)."""
        span = self.events.duration_us
        return self.events.count / (span * 1e-6) if span > 0 else 0.0

    @property
    def imu_rate_hz(self) -> float:
        """IMU samples per second (intervals / span), 0 with fewer than two samples."""
        span = self.imu.duration_us
        return (self.imu.count - 1) / (span * 1e-6) if span > 0 else 0.0

    @property
    def imu_mean_temperature_c(self) -> float | None:
        """Mean IMU temperature in °C, None without samples."""
        return self.imu_temperature_sum_c / self.imu.count if self.imu.count else None

    def to_dict(self) -> dict:
        """JSON-safe dictionary including the derived rates."""
        data = dataclasses.asdict(self)
        data.pop("imu_temperature_sum_c")
        data["event_rate_hz"] = self.event_rate_hz
        data["imu_rate_hz"] = self.imu_rate_hz
        data["imu_mean_temperature_c"] = self.imu_mean_temperature_c
        for name in ("events", "frames", "imu", "triggers"):
            data[name]["duration_us"] = getattr(self, name).duration_us
        return data


def summarize(source: PacketSource, gap_us: int = DEFAULT_GAP_US) -> RecordingSummary:
    """Read every packet of ``source`` and summarise it (pure apart from iterating the source).

    Args:
        source: any packet source (file reader, camera, emulator).
        gap_us: event-free stretches at least this long are listed in ``gaps``.
    """
    info = source.info
    summary = RecordingSummary(
        format=str(info.extra.get("format", info.origin.split(":")[0] or "unknown")),
        camera=info.camera,
        serial=info.serial,
        width=info.width,
        height=info.height,
        origin=info.origin,
        streams=list(info.extra.get("streams", [])),
    )
    for packet in source:
        summary.packets += 1
        summary.dropped_events += packet.dropped_events
        summary.notes += packet.notes
        _add_events(summary, packet.events, gap_us)
        for frame in packet.frames:
            _add_frame(summary, frame)
        summary.imu.add(packet.imu["t"])
        summary.triggers.add(packet.triggers["t"])
        for times in (packet.imu["t"], packet.triggers["t"]):
            summary.time_range_us = _widen(summary.time_range_us, times)
        summary.imu_temperature_sum_c += float(packet.imu["temperature_c"].sum(dtype=np.float64))
        kinds, counts = np.unique(packet.triggers["kind"], return_counts=True)
        for kind, count in zip(kinds.tolist(), counts.tolist(), strict=True):
            known = kind in TriggerKind._value2member_map_
            name = TriggerKind(kind).name if known else str(kind)
            summary.trigger_kinds[name] = summary.trigger_kinds.get(name, 0) + int(count)
    if not summary.streams:
        summary.streams = [
            name for name in ("events", "frames", "imu", "triggers") if getattr(summary, name).count
        ]
    return summary


def _add_events(summary: RecordingSummary, events: np.ndarray, gap_us: int) -> None:
    if len(events) == 0:
        return
    summary.event_packets += 1
    times = events["t"]
    previous = summary.events.last_us
    steps = np.diff(times, prepend=times[0] if previous is None else previous)
    for index in np.flatnonzero(steps >= gap_us).tolist():
        summary.gaps.append([int(times[index] - steps[index]), int(times[index])])
    summary.events.add(times)
    summary.on_events += int(np.count_nonzero(events["p"] > 0))
    summary.x_range = _widen(summary.x_range, events["x"])
    summary.y_range = _widen(summary.y_range, events["y"])
    summary.time_range_us = _widen(summary.time_range_us, times)


def _add_frame(summary: RecordingSummary, frame) -> None:
    summary.frames.add(np.array([frame.exposure_start_us]))
    image = frame.image
    kind = "gray" if image.ndim == 2 else f"{image.shape[2]}-channel"
    shape = f"{image.dtype} {kind} {image.shape[0]} x {image.shape[1]} ({frame.bit_depth}-bit)"
    if shape not in summary.frame_shapes:
        summary.frame_shapes.append(shape)
    summary.frame_exposure_starts_us.append(frame.exposure_start_us)
    summary.frame_exposures_us.append(frame.exposure_us)
    summary.frame_readouts_us.append(frame.readout_us)
    readout = np.array([frame.readout_start_us, frame.readout_end_us])
    summary.time_range_us = _widen(summary.time_range_us, readout)


def _widen(span: list[int] | None, values: np.ndarray) -> list[int] | None:
    if len(values) == 0:
        return span
    low, high = int(values.min()), int(values.max())
    return [low, high] if span is None else [min(span[0], low), max(span[1], high)]


def format_summary(summary: RecordingSummary) -> str:
    """Render a summary for a person: one fact per line, integers with thousands separators."""
    ev, fr, imu, tr = summary.events, summary.frames, summary.imu, summary.triggers
    serial = f" (serial {summary.serial})" if summary.serial else ""
    lines = [
        f"format      {summary.format}",
        f"camera      {summary.camera or 'unknown'}{serial}",
        f"resolution  {summary.width} x {summary.height}",
        f"streams     {', '.join(summary.streams) or 'none'}",
        f"time range  {_span(summary.time_range_us)}",
        f"events      {ev.count:,} in {summary.event_packets:,} packets, {summary.on_events:,} ON",
    ]
    if ev.count:
        lines += [
            f"  first/last  {ev.first_us} / {ev.last_us} µs ({ev.duration_us:,} µs)",
            f"  rate        {summary.event_rate_hz:,.0f} events/s",
            f"  x / y range {_span(summary.x_range, '..')} / {_span(summary.y_range, '..')}",
        ]
    lines.append(f"frames      {fr.count:,}  {'; '.join(summary.frame_shapes)}".rstrip())
    if fr.count:
        starts = np.array(summary.frame_exposure_starts_us)
        interval = f", interval {int(np.median(np.diff(starts))):,} µs" if fr.count > 1 else ""
        lines += [
            f"  exposure    {_spread(summary.frame_exposures_us)} µs{interval}",
            f"  readout     {_spread(summary.frame_readouts_us)} µs",
            f"  exposure starts {_listing(summary.frame_exposure_starts_us)} µs",
        ]
    temperature = summary.imu_mean_temperature_c
    lines.append(
        f"imu         {imu.count:,}"
        + (f" at {summary.imu_rate_hz:,.1f} Hz, mean {temperature:.1f} °C" if imu.count else "")
    )
    kinds = ", ".join(f"{count} {name}" for name, count in sorted(summary.trigger_kinds.items()))
    lines.append(f"triggers    {tr.count:,}" + (f": {kinds}" if kinds else ""))
    lines += _problems(summary)
    return "\n".join(lines)


def _problems(summary: RecordingSummary) -> list[str]:
    lines = []
    for name in ("events", "frames", "imu", "triggers"):
        if getattr(summary, name).non_monotonic:
            lines.append(
                f"WARNING     {getattr(summary, name).non_monotonic:,} {name} "
                "timestamps go backwards"
            )
    for start, end in summary.gaps:
        lines.append(f"gap         no events from {start} to {end} µs ({end - start:,} µs)")
    if summary.dropped_events:
        lines.append(f"dropped     {summary.dropped_events:,} events lost")
    lines += [f"note        {note}" for note in summary.notes]
    return lines


def _span(span: list[int] | None, joiner: str = " .. ") -> str:
    return "none" if span is None else f"{span[0]}{joiner}{span[1]}"


def _spread(values: list[int]) -> str:
    low, high = min(values), max(values)
    return f"{low:,}" if low == high else f"{low:,} .. {high:,}"


def _listing(values: list[int], limit: int = 6) -> str:
    shown = ", ".join(str(v) for v in values[:limit])
    return shown + (f", ... ({len(values) - limit} more)" if len(values) > limit else "")
