"""Configuration requests on endpoint 0: 0xBF single read/write and 0xC2 multi-write, big-endian."""

from __future__ import annotations

import errno
import threading

import usb.core

from davis_io.errors import DeviceError
from davis_io.usb.protocol import (
    CONFIG_READ_REQUEST_TYPE,
    CONFIG_WRITE_REQUEST_TYPE,
    MULTI_WRITE_REQUEST,
    SINGLE_REQUEST,
)
from davis_io.usb.udev import install_hint

__all__ = [
    "ControlPort",
    "DeviceDisconnected",
    "DevicePermissionError",
    "DeviceStalled",
    "device_error",
]

_TIMEOUT_MS = 1000


class DeviceDisconnected(DeviceError):
    """The camera went away (unplugged, or the USB link died)."""


class DeviceStalled(DeviceError):
    """The data endpoint stalled; the stream cannot continue without reopening."""


class DevicePermissionError(DeviceError):
    """The operating system refused access to the camera."""


def device_error(error: usb.core.USBError, what: str) -> DeviceError:
    """Map a pyusb error to the typed error a user can act on."""
    if error.errno in (errno.ENODEV, errno.ENOENT):
        return DeviceDisconnected(f"{what}: camera disconnected ({error}); plug it in and reopen")
    if error.errno == errno.EPIPE:
        return DeviceStalled(f"{what}: endpoint stalled ({error}); close and reopen the camera")
    if error.errno == errno.EBUSY:
        return DeviceError(
            f"{what}: the camera is in use by another program ({error}); close that program first"
        )
    if error.errno in (errno.EACCES, errno.EPERM):
        return DevicePermissionError(
            f"{what}: permission denied ({error}); allow access with:\n  {install_hint()}"
        )
    return DeviceError(f"{what}: USB error ({error}); check the cable and reopen the camera")


class ControlPort:
    """Serialised configuration transfers to one device (safe to call from several threads)."""

    def __init__(self, device: usb.core.Device):
        self.device = device
        self._lock = threading.Lock()

    def read(self, module: int, param: int) -> int:
        """Read one 32-bit parameter (0xBF IN, big-endian reply of exactly 4 bytes)."""
        with self._lock:
            try:
                reply = self.device.ctrl_transfer(
                    CONFIG_READ_REQUEST_TYPE, SINGLE_REQUEST, module, param, 4, _TIMEOUT_MS
                )
            except usb.core.USBError as error:
                raise device_error(error, f"reading parameter {module}/{param}") from error
        if len(reply) != 4:
            raise DeviceError(
                f"reading parameter {module}/{param}: {len(reply)} bytes came back, "
                "4 expected; reopen the camera"
            )
        return int.from_bytes(bytes(reply), "big")

    def read64(self, module: int, param: int) -> int:
        """Read a 64-bit statistic (param = upper half, param + 1 = lower), retried if it moved."""
        while True:
            upper = self.read(module, param)
            lower = self.read(module, param + 1)
            if self.read(module, param) == upper:
                return upper << 32 | lower

    def write(self, module: int, param: int, value: int) -> None:
        """Write one 32-bit parameter (0xBF OUT, value big-endian)."""
        with self._lock:
            try:
                self.device.ctrl_transfer(
                    CONFIG_WRITE_REQUEST_TYPE,
                    SINGLE_REQUEST,
                    module,
                    param,
                    value.to_bytes(4, "big"),
                    _TIMEOUT_MS,
                )
            except usb.core.USBError as error:
                raise device_error(error, f"writing parameter {module}/{param}") from error

    def write_many(self, writes: list[tuple[int, int, int]]) -> None:
        """Write several parameters in one 0xC2 request (applied together by the device)."""
        payload = b"".join(bytes([m, p]) + v.to_bytes(4, "big") for m, p, v in writes)
        with self._lock:
            try:
                self.device.ctrl_transfer(
                    CONFIG_WRITE_REQUEST_TYPE,
                    MULTI_WRITE_REQUEST,
                    len(writes),
                    0,
                    payload,
                    _TIMEOUT_MS,
                )
            except usb.core.USBError as error:
                raise device_error(error, f"multi-write of {len(writes)} parameters") from error
