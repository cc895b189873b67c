"""Encoder from packets to DAVIS bulk-IN words: the inverse of ``words.WordDecoder``.

Used by the emulated device and to write raw bulk-IN dumps. Frames of any bit depth up to 10
become 10-bit ADC reads: a pixel value v at depth b is scaled to ``v10 = v << (10 - b)`` (an
8-bit value of DV, which is the 10-bit value >> 2, comes back as ``v10 >> 2 == v``), then
written as reset read 1023 and signal read ``1023 - v10``, so that correlated double sampling
gives back ``v10`` exactly (``v10 == 1023`` gives signal 0, which CDS maps to 1023 too).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.errors import UsageError
from davis_io.types import Frame, Packet, TriggerKind, empty_events
from davis_io.usb.assemble import ADC_MAX
from davis_io.usb.layout import SensorLayout
from davis_io.usb.protocol import Special

__all__ = ["EncoderStats", "StreamEncoder", "frame_words", "imu_words", "time_words"]

_MAX_WRAPS_PER_WORD = 0xFFF
_TRIGGER_SPECIALS = {
    TriggerKind.EXTERNAL_SIGNAL_FALLING_EDGE: Special.EXTERNAL_INPUT_FALLING_EDGE,
    TriggerKind.EXTERNAL_SIGNAL_RISING_EDGE: Special.EXTERNAL_INPUT_RISING_EDGE,
    TriggerKind.EXTERNAL_SIGNAL_PULSE: Special.EXTERNAL_INPUT_PULSE,
    TriggerKind.EXTERNAL_GENERATOR_FALLING_EDGE: Special.EXTERNAL_GENERATOR_FALLING_EDGE,
    TriggerKind.EXTERNAL_GENERATOR_RISING_EDGE: Special.EXTERNAL_GENERATOR_RISING_EDGE,
}


def time_words(previous_us: int, t_us: int) -> list[int]:
    """Wrap words (multiplier up to 4095 each) and the timestamp word moving time to ``t_us``."""
    wraps = (t_us >> 15) - (previous_us >> 15)
    words = []
    while wraps > 0:
        step = min(wraps, _MAX_WRAPS_PER_WORD)
        words.append(0x7000 | step)
        wraps -= step
    words.append(0x8000 | (t_us & 0x7FFF))
    return words


def frame_words(frame: Frame, layout: SensorLayout, exposure_cycles: int) -> dict[str, np.ndarray]:
    """Words of one frame, split by the marker each group follows.

    Returns:
        ``{"sof": ..., "soe": ..., "eoe": ..., "eof": ...}``: frame start with ROI, exposure
        words and every reset-read column; exposure start; exposure end with every signal-read
        column; frame end.
    """
    if layout.adc_doubling:
        raise UsageError(
            "cannot encode frames for a DAVIS240 layout: its doubled ADC samples "
            "cannot carry odd pixel values; encode as a DAVIS346"
        )
    if frame.bit_depth > 10 or frame.image.ndim != 2:
        raise UsageError(
            f"cannot encode a frame of depth {frame.bit_depth} and shape "
            f"{frame.image.shape}: DAVIS frames are 2-D with at most 10 bits"
        )
    height, width = frame.image.shape
    x0, y0 = frame.position
    values = frame.image.astype(np.uint16) << (10 - frame.bit_depth)
    values = values if layout.aps_invert_xy else values.T
    if layout.aps_flip_x:
        values = values[::-1, :]
    if layout.aps_flip_y:
        values = values[:, ::-1]
    roi = []
    for value in (x0, y0, x0 + width - 1, y0 + height - 1):
        roi += [0x5100 | (value >> 8), 0x5200 | (value & 0xFF)]
    exposure = [0x6000 | ((exposure_cycles >> shift) & 0x3FF) for shift in (0, 10, 20)]
    start = np.array([Special.APS_FRAME_START_GLOBAL, *roi, *exposure], dtype=np.uint16)
    reset = _columns(np.full(values.shape, ADC_MAX, np.uint16), Special.APS_RESET_COLUMN_START)
    signal = _columns(ADC_MAX - values, Special.APS_SIGNAL_COLUMN_START)
    return {
        "sof": np.concatenate([start, reset]),
        "soe": np.array([Special.APS_EXPOSURE_START], dtype=np.uint16),
        "eoe": np.concatenate([np.array([Special.APS_EXPOSURE_END], np.uint16), signal]),
        "eof": np.array([Special.APS_FRAME_END], dtype=np.uint16),
    }


def _columns(samples: np.ndarray, start_code: int) -> np.ndarray:
    columns, rows = samples.shape
    block = np.empty((columns, rows + 2), dtype=np.uint16)
    block[:, 0] = start_code
    block[:, 1:-1] = 0x4000 | samples
    block[:, -1] = Special.APS_COLUMN_END
    return block.ravel()


def imu_words(sample: np.void, layout: SensorLayout, accel_scale: int, gyro_scale: int):
    """Words of one IMU sample (start, config, 14 big-endian bytes, end) at full-scale indices."""
    signs = np.array(layout.imu_axis_signs, dtype=np.float64)
    accel = np.asarray(sample["acc_g"], np.float64) * signs * (16384.0 / 2**accel_scale)
    gyro = np.asarray(sample["gyro_dps"], np.float64) * signs * (131.072 / 2**gyro_scale)
    if layout.imu_type == 2:
        temperature = (float(sample["temperature_c"]) - 21.0) * 333.87
    else:
        temperature = (float(sample["temperature_c"]) - 35.0) * 340.0
    raw = np.clip(np.rint([*accel, temperature, *gyro]), -32768, 32767).astype(">i2")
    config = 0b11100000 | (accel_scale << 2) | gyro_scale
    data = [0x5000 | byte for byte in raw.tobytes()]
    return np.array([Special.IMU_START, 0x5300 | config, *data, Special.IMU_END], np.uint16)


@dataclass
class EncoderStats:
    """Counters of the encoder.

    Attributes:
        events: DVS events encoded.
        frames: frames encoded.
        imu_samples: IMU samples encoded.
        triggers: external-input and generator triggers encoded.
        skipped_triggers: APS and reset triggers not encoded (frames carry their own markers).
        words: words produced.
        late_records: records older than time already encoded (their time goes backwards).
    """

    events: int = 0
    frames: int = 0
    imu_samples: int = 0
    triggers: int = 0
    skipped_triggers: int = 0
    words: int = 0
    late_records: int = 0


class StreamEncoder:
    """Turns a sequence of packets into one time-ordered word stream (stateful, any packet split).

    Records are held back until every stream has moved ``hold_us`` past them, because a source
    delivers a frame only after its readout ends while its start-of-frame words belong before
    later events. Device time is source time minus ``time_origin_us``. Records at or after
    ``end_us`` (a timestamp reset) are left out, so a frame running past it stays incomplete.
    """

    def __init__(
        self,
        layout: SensorLayout,
        *,
        time_origin_us: int,
        adc_clock_mhz: float = 30.0,
        accel_scale: int = 1,
        gyro_scale: int = 1,
        hold_us: int = 200_000,
        end_us: int | None = None,
    ):
        self.layout = layout
        self.time_origin_us = time_origin_us
        self.adc_clock_mhz = adc_clock_mhz
        self.accel_scale, self.gyro_scale = accel_scale, gyro_scale
        self.hold_us = hold_us
        self.end_us = 2**62 if end_us is None else end_us
        self.stats = EncoderStats()
        self._time_us = 0
        self._row: int | None = None
        self._events: list[np.ndarray] = []
        self._blocks: list[tuple[int, int, np.ndarray]] = []
        self._sequence = 0
        self._latest_us = -(2**62)

    def push(self, packet: Packet) -> np.ndarray:
        """Add a packet; return the words of every record now older than the hold window."""
        self._collect(packet)
        return self._emit(self._latest_us - self.hold_us)

    def flush(self) -> np.ndarray:
        """Return the words of every record still held back."""
        return self._emit(2**62)

    def encode_all(self, packets) -> np.ndarray:
        """Encode a whole sequence of packets into one word array."""
        parts = [self.push(packet) for packet in packets]
        return np.concatenate([*parts, self.flush()])

    def timestamp_reset_words(self, t_us: int) -> np.ndarray:
        """Words moving device time to source time ``t_us`` followed by a timestamp reset."""
        words = time_words(self._time_us, t_us - self.time_origin_us) + [Special.TIMESTAMP_RESET]
        self._time_us = t_us - self.time_origin_us
        return np.array(words, dtype=np.uint16)

    @property
    def device_time_us(self) -> int:
        """Device time of the last time word produced, µs."""
        return self._time_us

    def _block(self, t_us: int, words: np.ndarray) -> None:
        if t_us >= self.end_us:
            return
        self._blocks.append((t_us - self.time_origin_us, self._sequence, words))
        self._sequence += 1
        self._latest_us = max(self._latest_us, t_us)

    def _collect(self, packet: Packet) -> None:
        events = packet.events[packet.events["t"] < self.end_us]
        if len(events):
            self._events.append(events)
            self._latest_us = max(self._latest_us, int(events["t"][-1]))
        for frame in packet.frames:
            cycles = round(frame.exposure_us * self.adc_clock_mhz)
            words = frame_words(frame, self.layout, cycles)
            self._block(frame.readout_start_us, words["sof"])
            self._block(frame.exposure_start_us, words["soe"])
            self._block(frame.exposure_end_us, words["eoe"])
            self._block(frame.readout_end_us, words["eof"])
            self.stats.frames += 1
        for sample in packet.imu:
            self._block(
                int(sample["t"]), imu_words(sample, self.layout, self.accel_scale, self.gyro_scale)
            )
            self.stats.imu_samples += 1
        for t_us, kind in zip(
            packet.triggers["t"].tolist(), packet.triggers["kind"].tolist(), strict=True
        ):
            if kind in _TRIGGER_SPECIALS:
                self._block(t_us, np.array([_TRIGGER_SPECIALS[kind]], dtype=np.uint16))
                self.stats.triggers += 1
            else:
                self.stats.skipped_triggers += 1

    def _emit(self, horizon_us: int) -> np.ndarray:
        events = np.concatenate(self._events) if self._events else empty_events()
        cut = int(np.searchsorted(events["t"], horizon_us, side="right"))
        ready, held = events[:cut], events[cut:]
        self._events = [held] if len(held) else []
        horizon_device = horizon_us - self.time_origin_us
        self._blocks.sort(key=lambda block: block[:2])
        n_ready = sum(1 for block in self._blocks if block[0] <= horizon_device)
        blocks, self._blocks = self._blocks[:n_ready], self._blocks[n_ready:]
        device_t = ready["t"] - self.time_origin_us
        starts = np.searchsorted(device_t, [block[0] for block in blocks], side="left").tolist()
        parts, done = [], 0
        for start, (t_us, _, words) in zip(starts, blocks, strict=True):
            parts.append(self._event_words(ready[done:start], device_t[done:start]))
            done = start
            self.stats.late_records += int(t_us < self._time_us)
            if t_us != self._time_us:
                parts.append(np.array(time_words(self._time_us, t_us), dtype=np.uint16))
                self._time_us = t_us
            parts.append(words)
        parts.append(self._event_words(ready[done:], device_t[done:]))
        out = np.concatenate(parts) if parts else np.empty(0, np.uint16)
        self.stats.words += len(out)
        return out

    def _event_words(self, events: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Vectorised words of a run of events: wraps, timestamp, row (when it changes), column."""
        n = len(events)
        if n == 0:
            return np.empty(0, np.uint16)
        self.stats.late_records += int(np.count_nonzero(t < self._time_us))
        if self.layout.dvs_invert_xy:
            rows, columns = events["x"].astype(np.int64), events["y"].astype(np.int64)
        else:
            rows, columns = events["y"].astype(np.int64), events["x"].astype(np.int64)
        previous_t = np.concatenate([[self._time_us], t[:-1]])
        previous_row = np.concatenate([[-1 if self._row is None else self._row], rows[:-1]])
        wraps = (t >> 15) - (previous_t >> 15)
        wrap_words = np.maximum(-(-wraps // _MAX_WRAPS_PER_WORD), 0)
        new_time = (t != previous_t).astype(np.int64)
        new_row = (rows != previous_row).astype(np.int64)
        ends = np.cumsum(wrap_words + new_time + new_row + 1)
        out = np.empty(int(ends[-1]), dtype=np.uint16)
        out[ends - 1] = ((2 + (events["p"] > 0)) << 12) | columns
        out[(ends - 2)[new_row == 1]] = 0x1000 | rows[new_row == 1]
        has_time = new_time == 1
        out[(ends - 2 - new_row)[has_time]] = 0x8000 | (t[has_time] & 0x7FFF)
        for index in np.flatnonzero(wrap_words).tolist():
            first = ends[index] - 1 - new_row[index] - new_time[index] - wrap_words[index]
            words = time_words(int(previous_t[index]), int(t[index]))[:-1]
            out[first : first + len(words)] = words
        self._time_us, self._row = int(t[-1]), int(rows[-1])
        self.stats.events += n
        return out
