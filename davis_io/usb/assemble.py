"""Order-dependent state machines of the word stream: APS frame assembly and IMU sample assembly."""

from __future__ import annotations

import numpy as np

from davis_io.types import IMU_DTYPE, Frame
from davis_io.usb.layout import SensorLayout

__all__ = ["ADC_MAX", "CDS_RESET_MIN", "FrameAssembler", "ImuAssembler", "correlated_double_sample"]

ADC_MAX = 1023
"""Largest 10-bit ADC value; also what a saturated pixel becomes."""
CDS_RESET_MIN = 384
"""A reset read below this value marks the pixel saturated (set to ADC_MAX)."""

RESET_READ, SIGNAL_READ = 0, 1
IMU_BYTES = 14


def correlated_double_sample(reset: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """Apply the DAVIS CDS rule to reset and signal reads.

    Args:
        reset: reset-read ADC samples (any integer shape).
        signal: signal-read ADC samples, same shape.

    Returns:
        ``uint16`` pixel values 0-1023: ``reset - signal`` clamped, or 1023 where
        ``reset < 384`` or ``signal == 0`` (saturated).
    """
    reset = reset.astype(np.int32)
    signal = signal.astype(np.int32)
    value = np.clip(reset - signal, 0, ADC_MAX)
    saturated = (reset < CDS_RESET_MIN) | (signal == 0)
    return np.where(saturated, ADC_MAX, value).astype(np.uint16)


class FrameAssembler:
    """Builds APS frames from frame markers, ROI words, column markers and ADC samples."""

    def __init__(self, layout: SensorLayout):
        self.layout = layout
        self.roi = (0, 0, layout.aps_columns - 1, layout.aps_rows - 1)
        self._resize()
        self.start(0)
        self.active = False

    def _resize(self) -> None:
        start_col, start_row, end_col, end_row = self.roi
        width, height = end_col - start_col + 1, end_row - start_row + 1
        columns, samples = (height, width) if self.layout.aps_invert_xy else (width, height)
        self.shape = (columns, samples)
        self.reads = np.zeros((2, columns, samples), dtype=np.int32)

    def start(self, t_us: int) -> None:
        """Frame start (special 8/9): reset counters, ROI word sequence and exposure."""
        self.active = True
        self.times: dict[str, int | None] = {"sof": t_us, "soe": None, "eoe": None}
        self.readout = RESET_READ
        self.columns = [0, 0]
        self.rows = [0, 0]
        self.roi_words: list[int] = []
        self.pending_high = 0
        self.exposure_words = 0
        self.exposure_cycles = 0
        self.reads[:] = 0

    def roi_byte(self, high: bool, byte: int) -> None:
        """Misc-8 sub-code 1 (high byte) or 2 (low byte) of the four ROI values."""
        if not self.active:
            return
        if high:
            self.pending_high = byte
            return
        self.roi_words.append((self.pending_high << 8) | byte)
        if len(self.roi_words) == 4:
            self._apply_roi(*self.roi_words)

    def _apply_roi(self, start_col: int, start_row: int, end_col: int, end_row: int) -> None:
        full_w, full_h = self.layout.aps_columns, self.layout.aps_rows
        width, height = end_col - start_col + 1, end_row - start_row + 1
        if not 0 < width <= full_w:
            width = full_w
        if not 0 < height <= full_h:
            height = full_h
        if start_col + width > full_w:
            start_col = 0
        if start_row + height > full_h:
            start_row = 0
        self.roi = (start_col, start_row, start_col + width - 1, start_row + height - 1)
        self._resize()

    def exposure_word(self, value: int) -> None:
        """Misc-10 sub-code 0: next 10 bits (least significant first) of the exposure in cycles."""
        self.exposure_cycles |= value << (10 * self.exposure_words)
        self.exposure_words += 1

    def mark(self, name: str, t_us: int) -> None:
        """Exposure start (``"soe"``) or end (``"eoe"``) marker."""
        self.times[name] = t_us

    def column_start(self, readout: int) -> None:
        """Special 11 (reset read) or 12 (signal read): open a column of that readout type."""
        self.readout = readout
        self.rows[readout] = 0

    def column_end(self) -> None:
        """Special 13: close the current column."""
        self.columns[self.readout] += 1

    def samples(self, values: np.ndarray) -> None:
        """Code-4 words: the next samples down the current column; extra samples are ignored."""
        readout, column, row = self.readout, self.columns[self.readout], self.rows[self.readout]
        n_columns, n_samples = self.shape
        if column < n_columns and row < n_samples:
            take = min(len(values), n_samples - row)
            self.reads[readout, column, row : row + take] = values[:take]
        self.rows[readout] = row + len(values)

    def end(self, t_us: int) -> Frame | None:
        """Frame end (special 10): the frame if both readout types are complete, else None."""
        self.active = False
        if self.columns != [self.shape[0]] * 2:
            return None
        reads = self.reads << 1 if self.layout.adc_doubling else self.reads
        values = correlated_double_sample(reads[RESET_READ], reads[SIGNAL_READ])
        if self.layout.aps_flip_x:
            values = values[::-1, :]
        if self.layout.aps_flip_y:
            values = values[:, ::-1]
        image = values if self.layout.aps_invert_xy else values.T
        sof = self.times["sof"]
        soe = sof if self.times["soe"] is None else self.times["soe"]
        eoe = t_us if self.times["eoe"] is None else self.times["eoe"]
        return Frame(
            image=np.ascontiguousarray(image),
            exposure_start_us=soe,
            exposure_end_us=eoe,
            readout_start_us=sof,
            readout_end_us=t_us,
            bit_depth=10,
            position=(self.roi[0], self.roi[1]),
        )


class ImuAssembler:
    """Builds IMU samples from the IMU start/end specials and misc-8 IMU words."""

    def __init__(self, layout: SensorLayout):
        self.layout = layout
        self.raw = bytearray(IMU_BYTES)
        self.count = 0
        self.accel_scale = 0
        self.gyro_scale = 0
        self.enabled = 0b111

    def start(self) -> None:
        """Special 5: clear the sample."""
        self.raw[:] = bytes(IMU_BYTES)
        self.count = 0

    def config(self, byte: int) -> None:
        """Misc-8 sub-code 3: full-scale indices and enabled sensors; sets the byte counter."""
        self.gyro_scale = byte & 0b11
        self.accel_scale = (byte >> 2) & 0b11
        self.enabled = byte >> 5
        self.count = self._next_position(0)

    def _next_position(self, position: int) -> int:
        temperature, gyro, accel = self.enabled & 1, self.enabled & 2, self.enabled & 4
        if position == 0 and not accel:
            position = 6
        if position == 6 and not temperature:
            position = 8
        if position == 8 and not gyro:
            position = IMU_BYTES
        return position

    def byte(self, byte: int) -> None:
        """Misc-8 sub-code 0: the next byte of the big-endian 16-bit values."""
        if self.count >= IMU_BYTES:
            return
        self.raw[self.count] = byte
        self.count = self._next_position(self.count + 1)

    def end(self, t_us: int) -> np.ndarray | None:
        """Special 7: one ``IMU_DTYPE`` record if exactly 14 bytes were counted, else None."""
        if self.count != IMU_BYTES:
            return None
        raw = np.frombuffer(bytes(self.raw), dtype=">i2").astype(np.float64)
        signs = np.array(self.layout.imu_axis_signs, dtype=np.float64)
        sample = np.zeros(1, dtype=IMU_DTYPE)
        sample["t"] = t_us
        sample["acc_g"] = raw[0:3] * signs / (16384.0 / 2**self.accel_scale)
        sample["gyro_dps"] = raw[4:7] * signs / (131.072 / 2**self.gyro_scale)
        if self.layout.imu_type == 2:
            sample["temperature_c"] = raw[3] / 333.87 + 21.0
        else:
            sample["temperature_c"] = raw[3] / 340.0 + 35.0
        return sample
