"""The built-in DAVIS346 emulator: analytic HDR scenes, hand shake, APS and DVS models, truth."""

from davis_io.emulator.config import EmulatorConfig
from davis_io.emulator.dvs import DVS_PRESETS, DvsParams, DvsPixels
from davis_io.emulator.response import RESPONSE_CURVES, Response
from davis_io.emulator.scene import Scene
from davis_io.emulator.scenes import SCENES, get_scene
from davis_io.emulator.sensor import SENSOR_KINDS, Sensor, draw_sensor
from davis_io.emulator.source import EmulatedCamera

__all__ = [
    "DVS_PRESETS",
    "RESPONSE_CURVES",
    "SCENES",
    "SENSOR_KINDS",
    "DvsParams",
    "DvsPixels",
    "EmulatedCamera",
    "EmulatorConfig",
    "Response",
    "Scene",
    "Sensor",
    "draw_sensor",
    "get_scene",
]
