"""An emulated DAVIS346 behind pyusb's backend interface (``usb.core.find(backend=...)``)."""

from __future__ import annotations

import array
import errno
from types import SimpleNamespace

import usb.backend
import usb.core
import usb.util

from davis_io.usb import protocol as P
from davis_io.usb.emulated_device import EmulatedDavis346, RegisterRequest, usb_error
from davis_io.usb.emulated_stream import StreamFaults, looped_words

__all__ = ["EmulatedBackend", "EmulatedDavis346", "RegisterRequest", "StreamFaults", "looped_words"]

_LANGUAGE_EN_US = 0x0409
_GET_DESCRIPTOR = 0x06
_STRING_DESCRIPTOR = 0x03


class EmulatedBackend(usb.backend.IBackend):
    """pyusb backend serving emulated cameras: pass it as ``usb.core.find(backend=...)``."""

    def __init__(self, *devices: EmulatedDavis346):
        super().__init__()
        self.devices = list(devices)

    def enumerate_devices(self):  # noqa: D102 (pyusb interface)
        return [device for device in self.devices if device.connected]

    def get_device_descriptor(self, dev):  # noqa: D102
        return SimpleNamespace(
            bLength=18,
            bDescriptorType=1,
            bcdUSB=0x0300,
            bDeviceClass=0,
            bDeviceSubClass=0,
            bDeviceProtocol=0,
            bMaxPacketSize0=9,
            idVendor=P.VENDOR_ID,
            idProduct=dev.product_id,
            bcdDevice=dev.firmware,
            iManufacturer=1,
            iProduct=2,
            iSerialNumber=3,
            bNumConfigurations=1,
            address=dev.address,
            bus=1,
            port_number=dev.address,
            port_numbers=(dev.address,),
            speed=usb.util.SPEED_SUPER,
        )

    def get_configuration_descriptor(self, dev, config):  # noqa: D102
        return SimpleNamespace(
            bLength=9,
            bDescriptorType=2,
            wTotalLength=32,
            bNumInterfaces=1,
            bConfigurationValue=P.USB_CONFIGURATION,
            iConfiguration=0,
            bmAttributes=0x80,
            bMaxPower=112,
            extra_descriptors=[],
        )

    def get_interface_descriptor(self, dev, intf, alt, config):  # noqa: D102
        return SimpleNamespace(
            bLength=9,
            bDescriptorType=4,
            bInterfaceNumber=P.INTERFACE,
            bAlternateSetting=0,
            bNumEndpoints=2,
            bInterfaceClass=0xFF,
            bInterfaceSubClass=0,
            bInterfaceProtocol=0,
            iInterface=0,
            extra_descriptors=[],
        )

    def get_endpoint_descriptor(self, dev, ep, intf, alt, config):  # noqa: D102
        address, attributes, size = ((P.BULK_IN_ENDPOINT, 2, 1024), (0x81, 3, 64))[ep]
        return SimpleNamespace(
            bLength=7,
            bDescriptorType=5,
            bEndpointAddress=address,
            bmAttributes=attributes,
            wMaxPacketSize=size,
            bInterval=0,
            bRefresh=0,
            bSynchAddress=0,
            extra_descriptors=[],
        )

    def open_device(self, dev):  # noqa: D102
        if not dev.connected:
            raise usb_error("gone")
        if dev.deny_access:
            raise usb_error("access")
        dev.is_open = True
        return dev

    def close_device(self, dev_handle):  # noqa: D102
        dev_handle.is_open = False

    def set_configuration(self, dev_handle, config_value):  # noqa: D102
        if not dev_handle.connected:
            raise usb_error("gone")

    def get_configuration(self, dev_handle):  # noqa: D102
        return P.USB_CONFIGURATION

    def set_interface_altsetting(self, dev_handle, intf, altsetting):  # noqa: D102
        pass

    def claim_interface(self, dev_handle, intf):  # noqa: D102
        if not dev_handle.connected:
            raise usb_error("gone")
        if dev_handle.in_use_elsewhere:
            raise usb_error("busy")
        dev_handle.claimed = True

    def release_interface(self, dev_handle, intf):  # noqa: D102
        dev_handle.claimed = False
        if not dev_handle.connected:
            raise usb_error("gone")

    def is_kernel_driver_active(self, dev_handle, intf):  # noqa: D102
        return False

    def clear_halt(self, dev_handle, ep):  # noqa: D102
        if not dev_handle.connected:
            raise usb_error("gone")
        dev_handle.stalled = False
        dev_handle.clear_halt_count += 1

    def bulk_read(self, dev_handle, ep, intf, buff, timeout):  # noqa: D102
        data = dev_handle.bulk_read(len(buff), timeout)
        buff[: len(data)] = array.array("B", data)
        return len(data)

    def ctrl_transfer(  # noqa: D102
        self, dev_handle, bmRequestType, bRequest, wValue, wIndex, data, timeout
    ):
        if not dev_handle.connected:
            raise usb_error("gone")
        if bmRequestType == 0x80 and bRequest == _GET_DESCRIPTOR:
            return _fill(data, _string_descriptor(dev_handle, wValue & 0xFF))
        if bmRequestType == P.CONFIG_READ_REQUEST_TYPE and bRequest == P.SINGLE_REQUEST:
            value = dev_handle.read_register(wValue, wIndex)
            return _fill(data, value.to_bytes(4, "big"))
        if bmRequestType == P.CONFIG_WRITE_REQUEST_TYPE and bRequest == P.SINGLE_REQUEST:
            dev_handle.write_registers(bRequest, [(wValue, wIndex, int.from_bytes(data, "big"))])
            return len(data)
        if bmRequestType == P.CONFIG_WRITE_REQUEST_TYPE and bRequest == P.MULTI_WRITE_REQUEST:
            raw = bytes(data)
            entries = [
                (raw[i], raw[i + 1], int.from_bytes(raw[i + 2 : i + 6], "big"))
                for i in range(0, 6 * wValue, 6)
            ]
            dev_handle.write_registers(bRequest, entries)
            return len(data)
        raise usb.core.USBError("Pipe error (request not supported)", -9, errno.EPIPE)


def _string_descriptor(dev: EmulatedDavis346, index: int) -> bytes:
    if index == 0:
        body = _LANGUAGE_EN_US.to_bytes(2, "little")
    else:
        body = {1: "iniVation", 2: "DAVIS FX3", 3: dev.serial}.get(index, "").encode("utf-16-le")
    return bytes([2 + len(body), _STRING_DESCRIPTOR]) + body


def _fill(buffer, payload: bytes) -> int:
    count = min(len(buffer), len(payload))
    buffer[:count] = array.array("B", payload[:count])
    return count
