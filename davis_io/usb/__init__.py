"""DAVIS cameras over USB (pyusb): discovery, configuration, streaming, an emulated DAVIS346."""

from davis_io.usb.config import ApsConfig, DavisConfig, DvsConfig, ImuConfig, UsbConfig
from davis_io.usb.control import DeviceDisconnected, DevicePermissionError, DeviceStalled
from davis_io.usb.device import DavisCamera, open_camera
from davis_io.usb.discovery import CameraListing, default_backend, list_cameras
from davis_io.usb.dump import open_raw_usb_dump, write_raw_usb_dump
from davis_io.usb.layout import SensorLayout
from davis_io.usb.words import DecoderStats, WordDecoder

__all__ = [
    "ApsConfig",
    "CameraListing",
    "DavisCamera",
    "DavisConfig",
    "DecoderStats",
    "DeviceDisconnected",
    "DevicePermissionError",
    "DeviceStalled",
    "DvsConfig",
    "ImuConfig",
    "SensorLayout",
    "UsbConfig",
    "WordDecoder",
    "default_backend",
    "list_cameras",
    "open_camera",
    "open_raw_usb_dump",
    "write_raw_usb_dump",
]
