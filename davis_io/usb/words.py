"""Decoder of the DAVIS bulk-IN word stream: vectorised for events, a state machine elsewhere."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.types import EVENT_DTYPE, IMU_DTYPE, TRIGGER_DTYPE, Frame, Packet, TriggerKind
from davis_io.usb.assemble import RESET_READ, SIGNAL_READ, FrameAssembler, ImuAssembler
from davis_io.usb.layout import SensorLayout
from davis_io.usb.protocol import TIMESTAMP_WRAP_US, Code, Special

__all__ = ["DecoderStats", "WordDecoder"]

_TIMESTAMP_RESET_WORD = 0x0001
"""Code 0 (special), data 1: timestamp reset."""
_FOUR = np.uint16(Code.APS_SAMPLE)

_SPECIAL_TRIGGERS = {
    Special.EXTERNAL_INPUT_FALLING_EDGE: TriggerKind.EXTERNAL_SIGNAL_FALLING_EDGE,
    Special.EXTERNAL_INPUT_RISING_EDGE: TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE,
    Special.EXTERNAL_INPUT_PULSE: TriggerKind.EXTERNAL_SIGNAL_PULSE,
    Special.EXTERNAL_GENERATOR_FALLING_EDGE: TriggerKind.EXTERNAL_GENERATOR_FALLING_EDGE,
    Special.EXTERNAL_GENERATOR_RISING_EDGE: TriggerKind.EXTERNAL_GENERATOR_RISING_EDGE,
}


@dataclass
class DecoderStats:
    """Counters of everything the decoder saw, skipped or dropped (all cumulative).

    Attributes:
        words: 16-bit words decoded.
        events: DVS events emitted.
        frames: complete frames emitted.
        imu_samples: IMU samples emitted.
        frames_dropped: frames discarded (incomplete column counts, or cut by a timestamp reset).
        imu_dropped: IMU samples discarded (byte count at IMU end not 14, or cut by a reset).
        out_of_range_addresses: row or column words at or beyond the DVS array size.
        columns_without_row: column words before any valid row word (no event possible).
        unknown_words: special or misc codes that logic 18 does not define.
        split_words: words whose two bytes arrived in different transfers.
        trailing_bytes: a last odd byte at the end of the stream (no second half ever came).
        timestamp_resets: timestamp-reset specials.
        non_monotonic_times: timestamp or wrap words that moved time backwards (logged only).
    """

    words: int = 0
    events: int = 0
    frames: int = 0
    imu_samples: int = 0
    frames_dropped: int = 0
    imu_dropped: int = 0
    out_of_range_addresses: int = 0
    columns_without_row: int = 0
    unknown_words: int = 0
    split_words: int = 0
    trailing_bytes: int = 0
    timestamp_resets: int = 0
    non_monotonic_times: int = 0


class WordDecoder:
    """Turns bulk-IN bytes into packets; all state carries over from one call to the next.

    Time: device timestamp and wrap words build an unbounded µs count. A timestamp reset zeroes
    every part of it (wrap sum and current time). The first reset is time zero, whatever came
    before it (start-up left-overs); after a later one the decoder continues its output time
    line from the last time seen, so output times never go backwards. Each reset is marked with
    a ``TIMESTAMP_RESET`` trigger.
    APS and IMU data are ignored from the start and after each reset until the next frame start
    or IMU start, as libcaer does.
    """

    def __init__(self, layout: SensorLayout):
        self.layout = layout
        self.stats = DecoderStats()
        self._pending = b""
        self._epoch_us = 0
        self._origin_set = False
        self._wrap_add_us = 0
        self._device_us = 0
        self._last_row: int | None = None
        self._frames = FrameAssembler(layout)
        self._imu = ImuAssembler(layout)
        self._ignore_aps = True
        self._ignore_imu = True

    @property
    def time_us(self) -> int:
        """Output time of the last timestamp seen, µs."""
        return self._epoch_us + self._device_us

    @property
    def frame_exposure_cycles(self) -> int:
        """Exposure of the latest frame as its misc-10 words gave it, ADC clock cycles."""
        return self._frames.exposure_cycles

    def decode(self, data: bytes | bytearray | memoryview) -> Packet:
        """Decode one transfer (any length, any split point) into a packet."""
        buffer = self._pending + bytes(data) if self._pending else bytes(data)
        if self._pending and len(data):
            self.stats.split_words += 1
        usable = len(buffer) & ~1
        self._pending = buffer[usable:]
        words = np.frombuffer(buffer, dtype="<u2", count=usable // 2)
        out = _Output()
        resets = np.flatnonzero(words == _TIMESTAMP_RESET_WORD)
        start = 0
        for reset in resets:
            self._decode_segment(words[start:reset], out)
            self._timestamp_reset(out)
            start = reset + 1
        self._decode_segment(words[start:], out)
        self.stats.words += len(words)
        return out.packet()

    def finish(self) -> Packet:
        """End of stream: count a leftover odd byte; return a packet of notes (no records)."""
        packet = Packet()
        if self._pending:
            self.stats.trailing_bytes += len(self._pending)
            packet.notes.append("stream ended with half a word (1 byte dropped)")
            self._pending = b""
        return packet

    def _decode_segment(self, words: np.ndarray, out: _Output) -> None:
        codes = words >> 12
        time_positions, times = self._time_words(words, codes)
        out.events.append(self._events(words, codes, time_positions, times))
        # Codes for the state machine: special (0) and APS sample, misc-8, misc-10 (4, 5, 6);
        # codes - 4 wraps around below 4 in uint16, so one comparison finds 4..6.
        structure = np.flatnonzero((codes == Code.SPECIAL) | ((codes - _FOUR) < 3))
        if len(structure):
            self._structure(words, codes, structure, time_positions, times, out)
        if len(times):
            self._device_us = int(times[-1])

    def _time_words(self, words: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        positions = np.flatnonzero(codes >= Code.WRAP)  # wrap words and timestamp words
        values = words[positions]
        is_wrap = values < 0x8000
        increments = np.where(is_wrap, (values & 0xFFF).astype(np.int64) * TIMESTAMP_WRAP_US, 0)
        wrap_add = np.cumsum(increments) + self._wrap_add_us
        times = np.where(is_wrap, wrap_add, wrap_add + (values & 0x7FFF))
        if len(times):
            self._wrap_add_us = int(wrap_add[-1])
            steps = np.diff(times, prepend=self._device_us)
            self.stats.non_monotonic_times += int(np.count_nonzero(steps < 0))
        return positions, times

    def _times_at(self, positions: np.ndarray, time_positions, times) -> np.ndarray:
        """Output time in effect at each word position (set by the last time word before it)."""
        device = _value_in_effect(time_positions, times, positions, self._device_us)
        return device + self._epoch_us

    def _events(self, words, codes, time_positions, times) -> np.ndarray:
        layout = self.layout
        data = words & 0xFFF
        rows = np.flatnonzero(codes == Code.ROW)
        in_range = data[rows] < layout.dvs_rows
        if not in_range.all():
            self.stats.out_of_range_addresses += len(rows) - int(np.count_nonzero(in_range))
            rows = rows[in_range]
        columns = np.flatnonzero((codes >> 1) == 1)  # Code.COLUMN_OFF or Code.COLUMN_ON
        column_data = data[columns]
        carried_row = -1 if self._last_row is None else self._last_row
        row_data = _value_in_effect(rows, data[rows].astype(np.int32), columns, carried_row)
        if len(rows):
            self._last_row = int(data[rows[-1]])
        in_range = column_data < layout.dvs_columns
        has_row = row_data >= 0
        keep = in_range & has_row
        if not keep.all():
            self.stats.out_of_range_addresses += len(columns) - int(np.count_nonzero(in_range))
            self.stats.columns_without_row += int(np.count_nonzero(in_range & ~has_row))
            columns, column_data, row_data = columns[keep], column_data[keep], row_data[keep]
        events = np.empty(len(columns), dtype=EVENT_DTYPE)
        events["t"] = self._times_at(columns, time_positions, times)
        if layout.dvs_invert_xy:
            events["x"], events["y"] = row_data, column_data
        else:
            events["x"], events["y"] = column_data, row_data
        events["p"] = (codes[columns].astype(np.int8) << 1) - 5
        self.stats.events += len(events)
        return events

    def _timestamp_reset(self, out: _Output) -> None:
        # The first reset is time zero: start-up left-overs before it (a wrap word, a stale
        # timestamp) say nothing of the time since. A later one continues the output time line.
        self._epoch_us = self._epoch_us + self._device_us if self._origin_set else 0
        self._origin_set = True
        self._wrap_add_us = 0
        self._device_us = 0
        self.stats.timestamp_resets += 1
        if self._frames.active:
            self._frames.active = False
            self._drop_frame(out, "frame cut by a timestamp reset")
        if not self._ignore_imu and self._imu.count:
            self.stats.imu_dropped += 1
            out.notes.append("IMU sample cut by a timestamp reset")
        self._ignore_aps = self._ignore_imu = True
        out.trigger(self._epoch_us, TriggerKind.TIMESTAMP_RESET)

    def _drop_frame(self, out: _Output, why: str) -> None:
        self.stats.frames_dropped += 1
        out.notes.append(f"{why} at t={self.time_us} µs (frame dropped)")

    def _structure(self, words, codes, positions, time_positions, times, out: _Output) -> None:
        """Walk specials, misc words and APS sample runs in stream order."""
        is_sample = codes[positions] == Code.APS_SAMPLE
        markers = positions[~is_sample]
        samples = (words[positions[is_sample]] & 0xFFF).astype(np.int32)
        cuts = np.searchsorted(positions[is_sample], markers)
        marker_times = self._times_at(markers, time_positions, times).tolist()
        marker_words = words[markers].tolist()
        fed = 0
        for cut, word, t_us in zip(cuts.tolist(), marker_words, marker_times, strict=True):
            if cut > fed:
                self._feed_samples(samples[fed:cut])
                fed = cut
            self._marker(word, t_us, out)
        if len(samples) > fed:
            self._feed_samples(samples[fed:])

    def _feed_samples(self, samples: np.ndarray) -> None:
        if not self._ignore_aps and self._frames.active:
            self._frames.samples(samples)

    def _marker(self, word: int, t_us: int, out: _Output) -> None:
        code, data = word >> 12, word & 0xFFF
        if code == Code.SPECIAL:
            self._special(data, t_us, out)
        elif code == Code.MISC8:
            self._misc8(data >> 8, data & 0xFF)
        elif code == Code.MISC10 and (data >> 10) == 0:
            self._frames.exposure_word(data & 0x3FF)
        else:
            self.stats.unknown_words += 1

    def _misc8(self, subcode: int, byte: int) -> None:
        if subcode in (1, 2):
            self._frames.roi_byte(subcode == 1, byte)
        elif subcode == 0 and not self._ignore_imu:
            self._imu.byte(byte)
        elif subcode == 3 and not self._ignore_imu:
            self._imu.config(byte)
        elif subcode not in (0, 3):
            self.stats.unknown_words += 1

    def _special(self, code: int, t_us: int, out: _Output) -> None:
        frames = self._frames
        if code in (Special.APS_FRAME_START_GLOBAL, Special.APS_FRAME_START_ROLLING):
            if frames.active and not self._ignore_aps:
                self._drop_frame(out, "frame start before the previous frame ended")
            self._ignore_aps = False
            frames.start(t_us)
            out.trigger(t_us, TriggerKind.APS_FRAME_START)
        elif Special.APS_FRAME_END <= code <= Special.APS_EXPOSURE_END:
            if not self._ignore_aps:
                self._aps_special(code, t_us, out)
        elif code == Special.IMU_START:
            self._ignore_imu = False
            self._imu.start()
        elif code == Special.IMU_END:
            if not self._ignore_imu:
                self._imu_end(t_us, out)
        elif code in _SPECIAL_TRIGGERS:
            out.trigger(t_us, _SPECIAL_TRIGGERS[code])
        else:
            self.stats.unknown_words += 1

    def _aps_special(self, code: int, t_us: int, out: _Output) -> None:
        frames = self._frames
        if code == Special.APS_FRAME_END:
            out.trigger(t_us, TriggerKind.APS_FRAME_END)
            if not frames.active:
                return
            frame = frames.end(t_us)
            if frame is None:
                self._drop_frame(out, "frame with missing columns")
            else:
                self.stats.frames += 1
                out.frames.append(frame)
        elif code == Special.APS_RESET_COLUMN_START:
            frames.column_start(RESET_READ)
        elif code == Special.APS_SIGNAL_COLUMN_START:
            frames.column_start(SIGNAL_READ)
        elif code == Special.APS_COLUMN_END:
            frames.column_end()
        elif code == Special.APS_EXPOSURE_START:
            frames.mark("soe", t_us)
            out.trigger(t_us, TriggerKind.APS_EXPOSURE_START)
        else:
            frames.mark("eoe", t_us)
            out.trigger(t_us, TriggerKind.APS_EXPOSURE_END)

    def _imu_end(self, t_us: int, out: _Output) -> None:
        sample = self._imu.end(t_us)
        if sample is None:
            self.stats.imu_dropped += 1
            out.notes.append(f"incomplete IMU sample at t={t_us} µs (dropped)")
        else:
            self.stats.imu_samples += 1
            out.imu.append(sample)
        self._imu.start()


def _value_in_effect(setters: np.ndarray, values: np.ndarray, queries: np.ndarray, carried: int):
    """Value of the last setter at or before each query position (``carried`` before the first).

    Args:
        setters: sorted word positions that set a value.
        values: the value each setter sets.
        queries: sorted word positions to look up (never equal to a setter position).
        carried: value in effect before the first setter.
    """
    if not len(setters) or not len(queries):
        return np.full(len(queries), carried, dtype=values.dtype)
    first = setters[0]
    end = max(int(setters[-1]), int(queries[-1])) + 1
    filled = np.repeat(values, np.diff(setters, append=end))
    after_first = queries > first
    if after_first.all():
        return filled[queries - first]
    return np.where(after_first, filled[np.maximum(queries - first, 0)], carried)


class _Output:
    """Records collected during one ``decode`` call."""

    def __init__(self):
        self.events: list[np.ndarray] = []
        self.frames: list[Frame] = []
        self.imu: list[np.ndarray] = []
        self.triggers: list[tuple[int, int]] = []
        self.notes: list[str] = []

    def trigger(self, t_us: int, kind: TriggerKind) -> None:
        self.triggers.append((t_us, int(kind)))

    def packet(self) -> Packet:
        events = np.concatenate(self.events) if len(self.events) != 1 else self.events[0]
        imu = np.concatenate(self.imu) if self.imu else np.empty(0, dtype=IMU_DTYPE)
        triggers = np.array(self.triggers, dtype=TRIGGER_DTYPE)
        if not len(events):
            events = np.empty(0, dtype=EVENT_DTYPE)
        return Packet(
            events=events, frames=self.frames, imu=imu, triggers=triggers, notes=self.notes
        )
