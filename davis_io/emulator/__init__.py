"""The built-in DAVIS346 emulator: analytic HDR scenes, hand shake, APS and DVS models, truth."""

from davis_io.emulator.dvs import DVS_PRESETS, DvsParams, DvsPixels
from davis_io.emulator.response import RESPONSE_CURVES
from davis_io.emulator.scene import Scene
from davis_io.emulator.scenes import SCENES, get_scene
from davis_io.emulator.source import EmulatedCamera, EmulatorConfig
from davis_io.emulator.truth import Truth, load_truth, save_truth

__all__ = [
    "DVS_PRESETS",
    "RESPONSE_CURVES",
    "SCENES",
    "DvsParams",
    "DvsPixels",
    "EmulatedCamera",
    "EmulatorConfig",
    "Scene",
    "Truth",
    "get_scene",
    "load_truth",
    "save_truth",
]
