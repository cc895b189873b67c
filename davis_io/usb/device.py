"""``DavisCamera``: a DAVIS on USB as a packet source (open, configure, start, read, close)."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator

import usb.backend
import usb.core
import usb.util

from davis_io.colorfilter import DEVICE_COLOR_FILTERS
from davis_io.errors import DeviceError
from davis_io.types import Packet, SourceInfo
from davis_io.usb import protocol as P
from davis_io.usb.config import DavisConfig, DeviceFacts, config_writes, with_chip_biases
from davis_io.usb.control import ControlPort, device_error
from davis_io.usb.discovery import check_versions, choose_device, find_devices, read_serial
from davis_io.usb.layout import SensorLayout
from davis_io.usb.reader import StreamReader

__all__ = ["DavisCamera", "open_camera"]

_PRODUCERS_OFF = [
    (P.Module.DVS, P.Dvs.RUN),
    (P.Module.APS, P.Aps.RUN),
    (P.Module.IMU, P.Imu.RUN_ACCELEROMETER),
    (P.Module.IMU, P.Imu.RUN_GYROSCOPE),
    (P.Module.IMU, P.Imu.RUN_TEMPERATURE),
    (P.Module.EXTINPUT, P.ExtInput.RUN_DETECTOR),
    (P.Module.MUX, P.Mux.RUN),
    (P.Module.MUX, P.Mux.TIMESTAMP_RUN),
    (P.Module.USB, P.Usb.RUN),
    (P.Module.MUX, P.Mux.RUN_CHIP),
]
"""dataStart step 1 and dataStop: everything off, in this order."""
_PRODUCERS_ON = _PRODUCERS_OFF[:6]
"""dataStart step 7: DVS, APS, IMU accel/gyro/temperature, external-input detector."""


def open_camera(
    serial: str | None = None,
    config: DavisConfig | None = None,
    *,
    backend: usb.backend.IBackend | None = None,
    **options,
) -> DavisCamera:
    """Open the camera with ``serial`` (or the only one attached); use it as a context manager.

    Raises:
        DeviceError: no camera, several and no serial, unsupported versions, no permission.
    """
    device = choose_device(find_devices(backend), serial)
    return DavisCamera(device, config or DavisConfig(), **options)


class DavisCamera:
    """A DAVIS camera streaming packets; ``with open_camera() as camera: for packet in camera``.

    Opening checks versions and reads the sensor facts; entering sends the configuration and
    runs libcaer's start sequence; leaving runs the stop sequence, stops the reader thread and
    releases the interface, whatever happened. Iteration yields a packet per bulk transfer
    (an empty packet when nothing came for ``idle_s``), and ends with a ``DeviceError``
    subclass after every complete packet was delivered when the camera is unplugged or stalls.
    """

    def __init__(
        self,
        device: usb.core.Device,
        config: DavisConfig,
        *,
        queue_packets: int = 256,
        read_bytes: int = 131072,
        idle_s: float = 0.1,
        poll_s: float = 0.5,
    ):
        self.device = device
        self.config = config
        self.idle_s, self.poll_s = idle_s, poll_s
        self.serial = read_serial(device)
        self.port = ControlPort(device)
        self._claim()
        try:
            self.logic_version, self.logic_patch = check_versions(device, self.port, self.serial)
            self.facts = self._read_facts()
            self.config = with_chip_biases(config, self.facts)
            self.info = self._source_info()
        except BaseException:
            self._release()
            raise
        self.reader = StreamReader(device, self.facts.layout, queue_packets, read_bytes)
        self.device_drops = 0
        self._applied: DavisConfig | None = None
        self._last_poll = 0.0

    def _claim(self) -> None:
        try:
            if self.device.get_active_configuration().bConfigurationValue != P.USB_CONFIGURATION:
                self.device.set_configuration(P.USB_CONFIGURATION)
            usb.util.claim_interface(self.device, P.INTERFACE)
        except usb.core.USBError as error:
            raise device_error(error, f"opening DAVIS serial {self.serial}") from error

    def _release(self) -> None:
        try:
            usb.util.release_interface(self.device, P.INTERFACE)
        except usb.core.USBError:
            pass  # already gone: nothing left to release on the device side
        usb.util.dispose_resources(self.device)

    def _read_facts(self) -> DeviceFacts:
        read = self.port.read
        layout = SensorLayout(
            dvs_columns=read(P.Module.DVS, P.Dvs.SIZE_COLUMNS),
            dvs_rows=read(P.Module.DVS, P.Dvs.SIZE_ROWS),
            dvs_invert_xy=bool(read(P.Module.DVS, P.Dvs.ORIENTATION_INFO) & 0b100),
            aps_columns=read(P.Module.APS, P.Aps.SIZE_COLUMNS),
            aps_rows=read(P.Module.APS, P.Aps.SIZE_ROWS),
            aps_orientation=read(P.Module.APS, P.Aps.ORIENTATION_INFO),
            imu_type=read(P.Module.IMU, P.Imu.TYPE),
            imu_orientation=read(P.Module.IMU, P.Imu.ORIENTATION_INFO),
        )
        chip_id = read(P.Module.SYSINFO, P.SysInfo.CHIP_IDENTIFIER)
        if chip_id in P.DAVIS240_CHIP_IDS:
            layout = dataclasses.replace(layout, adc_doubling=True)
        deviation = read(P.Module.SYSINFO, P.SysInfo.CLOCK_DEVIATION) / 1000
        flags = [
            read(P.Module.DVS, flag)
            for flag in (
                P.Dvs.HAS_PIXEL_FILTER,
                P.Dvs.HAS_BACKGROUND_ACTIVITY_FILTER,
                P.Dvs.HAS_ROI_FILTER,
                P.Dvs.HAS_SKIP_FILTER,
                P.Dvs.HAS_POLARITY_FILTER,
            )
        ]
        self.color_register = read(P.Module.APS, P.Aps.COLOR_FILTER)
        return DeviceFacts(
            layout=layout,
            chip_id=chip_id,
            logic_clock_mhz=read(P.Module.SYSINFO, P.SysInfo.LOGIC_CLOCK) * deviation,
            adc_clock_mhz=read(P.Module.SYSINFO, P.SysInfo.ADC_CLOCK) * deviation,
            usb_clock_mhz=read(P.Module.SYSINFO, P.SysInfo.USB_CLOCK) * deviation,
            has_global_shutter=bool(read(P.Module.APS, P.Aps.HAS_GLOBAL_SHUTTER)),
            has_dvs_filters=all(flags),
            has_statistics=bool(read(P.Module.MUX, P.Mux.HAS_STATISTICS)),
        )

    def _source_info(self) -> SourceInfo:
        facts = self.facts
        if self.color_register >= len(DEVICE_COLOR_FILTERS):
            raise DeviceError(
                f"DAVIS serial {self.serial}: unknown colour filter register "
                f"value {self.color_register}"
            )
        return SourceInfo(
            camera=P.chip_name(facts.chip_id),
            serial=self.serial,
            width=facts.layout.width,
            height=facts.layout.height,
            color_filter=DEVICE_COLOR_FILTERS[self.color_register],
            origin="usb",
            firmware_version=self.device.bcdDevice & 0xFF,
            logic_version=self.logic_version,
            extra={
                "logic_patch": self.logic_patch,
                "chip_id": facts.chip_id,
                "adc_clock_mhz": facts.adc_clock_mhz,
                "logic_clock_mhz": facts.logic_clock_mhz,
                "usb_clock_mhz": facts.usb_clock_mhz,
                "config": dataclasses.asdict(self.config),
            },
        )

    def configure(self, config: DavisConfig) -> list[tuple[int, int, int]]:
        """Send only the registers that differ from what was last applied; return them."""
        writes = config_writes(self._applied, config, self.facts)
        for module, param, value in writes:
            self.port.write(module, param, value)
        self._applied = self.config = with_chip_biases(config, self.facts)
        self.info = dataclasses.replace(
            self.info, extra={**self.info.extra, "config": dataclasses.asdict(self.config)}
        )
        return writes

    def timestamp_reset(self) -> None:
        """Reset the device clock (one multi-write: TIMESTAMP_RESET 1 then 0)."""
        self.port.write_many(
            [(P.Module.MUX, P.Mux.TIMESTAMP_RESET, 1), (P.Module.MUX, P.Mux.TIMESTAMP_RESET, 0)]
        )

    def start(self) -> None:
        """Configure, then libcaer's dataStart: off, clear halt, read, chip, clocks, producers."""
        self.configure(self.config)
        for module, param in _PRODUCERS_OFF:
            self.port.write(module, param, 0)
        time.sleep(0.010)
        try:
            self.device.clear_halt(P.BULK_IN_ENDPOINT)
        except usb.core.USBError as error:
            raise device_error(error, "clearing the data endpoint") from error
        self.reader.start()
        self.port.write(P.Module.MUX, P.Mux.RUN_CHIP, 1)
        time.sleep(0.200)
        for module, param in (
            (P.Module.USB, P.Usb.RUN),
            (P.Module.MUX, P.Mux.TIMESTAMP_RUN),
            (P.Module.MUX, P.Mux.RUN),
        ):
            self.port.write(module, param, 1)
        time.sleep(0.050)
        for module, param in _PRODUCERS_ON:
            self.port.write(module, param, 1)

    def stop(self) -> None:
        """Libcaer's dataStop (every producer, clock and the chip off), then stop the reader."""
        try:
            for module, param in _PRODUCERS_OFF:
                self.port.write(module, param, 0)
        finally:
            self.reader.stop()

    def close(self) -> None:
        """Stop streaming (best effort when the camera is gone) and release the interface."""
        try:
            self.stop()
        except DeviceError:
            pass  # unplugged: the device has nothing left to switch off
        finally:
            self._release()

    def __enter__(self) -> DavisCamera:
        try:
            self.start()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close()

    def poll_drops(self) -> int:
        """Read the device's DVS drop counter; return the events dropped since the last poll.

        Returns 0 on devices without statistics (MUX HAS_STATISTICS = 0).
        """
        if not self.facts.has_statistics:
            return 0
        total = self.port.read64(P.Module.MUX, P.Mux.STATISTICS_DVS_DROPPED)
        new, self.device_drops = total - self.device_drops, total
        return new

    def __iter__(self) -> Iterator[Packet]:
        while True:
            packet = self.reader.next_packet(self.idle_s)
            if packet is None:
                return
            if packet.is_empty or time.monotonic() - self._last_poll >= self.poll_s:
                self._add_device_drops(packet)
            yield packet

    def _add_device_drops(self, packet: Packet) -> None:
        self._last_poll = time.monotonic()
        try:
            dropped = self.poll_drops()
        except DeviceError:
            return  # the reader reports the failure once every complete packet is out
        if dropped:
            packet.dropped_events += dropped
            packet.notes.append(f"camera dropped {dropped} DVS events (USB FIFO full)")
