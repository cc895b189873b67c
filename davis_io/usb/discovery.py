"""Finding DAVIS cameras on USB, reading their identity and versions, and choosing one to open."""

from __future__ import annotations

from dataclasses import dataclass

import usb.backend
import usb.core
import usb.util

from davis_io.errors import DeviceError
from davis_io.usb import protocol as P
from davis_io.usb.control import ControlPort, device_error

__all__ = [
    "CameraListing",
    "check_versions",
    "choose_device",
    "default_backend",
    "find_devices",
    "list_cameras",
    "read_serial",
]

_SPEEDS = {
    1: "low (1.5 Mbit/s)",
    2: "full (12 Mbit/s)",
    3: "high (480 Mbit/s)",
    4: "super (5 Gbit/s)",
    5: "super+ (10 Gbit/s)",
}
_MAX_SERIAL_CHARS = 8
_GET_DESCRIPTOR_IN, _GET_DESCRIPTOR, _STRING_LANGUAGES = 0x80, 0x06, 0x0300
"""Standard request reading string descriptor 0 (the language list)."""


def default_backend() -> usb.backend.IBackend:
    """The system's libusb-1.0, else the one bundled by ``libusb-package``.

    Raises:
        DeviceError: no libusb could be loaded.
    """
    import usb.backend.libusb1

    backend = usb.backend.libusb1.get_backend()
    if backend is None:
        import libusb_package

        backend = libusb_package.get_libusb1_backend()
    if backend is None:
        raise DeviceError(
            "no libusb-1.0 found: install it (apt install libusb-1.0-0) or "
            "reinstall the libusb-package Python package"
        )
    return backend


def find_devices(backend: usb.backend.IBackend | None = None) -> list[usb.core.Device]:
    """Every attached DAVIS (vendor 0x152A, product 0x841A or 0x841B)."""
    found = usb.core.find(find_all=True, idVendor=P.VENDOR_ID, backend=backend or default_backend())
    return [dev for dev in found if dev.idProduct in P.MIN_FIRMWARE]


def read_serial(device: usb.core.Device) -> str:
    """Serial-number string (``TMP<bus/address>`` when the device has none).

    Raises:
        DeviceError: the serial number is longer than 8 characters (not a DAVIS serial).
    """
    if not device.iSerialNumber:
        return f"TMP{(device.bus << 8) | device.address:05d}"
    try:
        serial = usb.util.get_string(device, device.iSerialNumber) or ""
    except usb.core.USBError as error:
        raise device_error(error, "reading the serial number") from error
    except ValueError as error:
        _raise_string_error(device)
        raise DeviceError(f"reading the serial number: {error}") from error
    if len(serial) > _MAX_SERIAL_CHARS:
        raise DeviceError(
            f"serial number {serial!r} is longer than {_MAX_SERIAL_CHARS} "
            "characters: not a DAVIS camera"
        )
    return serial


def _raise_string_error(device: usb.core.Device) -> None:
    """Pyusb hides why string descriptors failed: ask for the language list to get the errno."""
    try:
        device.ctrl_transfer(_GET_DESCRIPTOR_IN, _GET_DESCRIPTOR, _STRING_LANGUAGES, 0, 255)
    except usb.core.USBError as error:
        raise device_error(error, "reading the serial number") from error


def firmware_version(device: usb.core.Device) -> int:
    """Firmware version: the low byte of bcdDevice."""
    return device.bcdDevice & 0xFF


def check_versions(device: usb.core.Device, port: ControlPort, serial: str) -> tuple[int, int]:
    """Check firmware, logic version and patch; return ``(logic_version, logic_patch)``.

    Raises:
        DeviceError: a version is unsupported; the message names the version found and needed.
    """
    board = "FX3" if device.idProduct == P.FX3_PRODUCT_ID else "FX2"
    where = f"DAVIS {board} board, serial {serial}"
    firmware, needed = firmware_version(device), P.MIN_FIRMWARE[device.idProduct]
    if firmware < needed:
        raise DeviceError(
            f"{where}: firmware version {firmware} found, {needed} or newer needed; "
            "update it with iniVation's Flashy tool"
        )
    logic = port.read(P.Module.SYSINFO, P.SysInfo.LOGIC_VERSION)
    if logic != P.REQUIRED_LOGIC_VERSION:
        raise DeviceError(
            f"{where}: logic version {logic} found, exactly "
            f"{P.REQUIRED_LOGIC_VERSION} needed; update it with iniVation's Flashy"
        )
    patch = port.read(P.Module.SYSINFO, P.SysInfo.LOGIC_PATCH)
    if patch < P.MIN_LOGIC_PATCH:
        raise DeviceError(
            f"{where}: logic patch {patch} found, {P.MIN_LOGIC_PATCH} or newer "
            "needed; update it with iniVation's Flashy tool"
        )
    return logic, patch


def choose_device(devices: list[usb.core.Device], serial: str | None) -> usb.core.Device:
    """The device with ``serial`` (first 8 characters compared), or the only one attached.

    Raises:
        DeviceError: none attached, no such serial, or several attached and no serial given.
    """
    if not devices:
        raise DeviceError(
            "no DAVIS camera found (USB 152a:841a or 152a:841b); plug one in, "
            "then check `seecap devices` and `seecap doctor`"
        )
    if serial is None:
        if len(devices) > 1:
            serials = ", ".join(read_serial(dev) for dev in devices)
            raise DeviceError(
                f"{len(devices)} DAVIS cameras attached ({serials}); choose one with --serial"
            )
        return devices[0]
    for device in devices:
        if read_serial(device)[:_MAX_SERIAL_CHARS] == serial[:_MAX_SERIAL_CHARS]:
            return device
    found = ", ".join(read_serial(dev) for dev in devices)
    raise DeviceError(f"no DAVIS camera with serial {serial!r}; attached: {found}")


@dataclass(frozen=True)
class CameraListing:
    """One attached camera as ``seecap devices`` shows it.

    Attributes:
        model: chip name when it could be read, else the board family.
        serial: serial number ("" when unreadable).
        firmware: firmware version (bcdDevice low byte).
        logic: ``"18.1"`` style logic version and patch, "" when unreadable.
        speed: USB link speed.
        bus: USB bus number; ``address`` the device address.
        usable: the camera can be opened and its versions are supported.
        problem: why not, with what to do ("" when usable).
    """

    model: str
    serial: str
    firmware: int
    logic: str
    speed: str
    bus: int
    address: int
    usable: bool
    problem: str = ""


def list_cameras(backend: usb.backend.IBackend | None = None) -> list[CameraListing]:
    """Identify every attached DAVIS without streaming (each is opened and released)."""
    return [_describe(device) for device in find_devices(backend)]


def _try_claim(device: usb.core.Device, serial: str) -> None:
    """Claim and release interface 0: fails when another program holds the camera."""
    try:
        usb.util.claim_interface(device, P.INTERFACE)
        usb.util.release_interface(device, P.INTERFACE)
    except usb.core.USBError as error:
        raise device_error(error, f"opening DAVIS serial {serial}") from error


def _describe(device: usb.core.Device) -> CameraListing:
    board = "FX3 board" if device.idProduct == P.FX3_PRODUCT_ID else "FX2 board"
    facts = {"model": f"DAVIS ({board})", "serial": "", "logic": ""}
    problem = ""
    try:
        facts["serial"] = read_serial(device)
        _try_claim(device, facts["serial"])
        port = ControlPort(device)
        logic, patch = check_versions(device, port, facts["serial"])
        facts["logic"] = f"{logic}.{patch}"
        facts["model"] = P.chip_name(port.read(P.Module.SYSINFO, P.SysInfo.CHIP_IDENTIFIER))
    except DeviceError as error:
        problem = str(error)
    finally:
        usb.util.dispose_resources(device)
    return CameraListing(
        model=facts["model"],
        serial=facts["serial"],
        firmware=firmware_version(device),
        logic=facts["logic"],
        speed=_SPEEDS.get(device.speed or 0, "unknown"),
        bus=device.bus,
        address=device.address,
        usable=not problem,
        problem=problem,
    )
