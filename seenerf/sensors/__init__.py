"""Sensor models: the exposure integral, the RGB response and the event response (pure + module)."""

from seenerf.sensors.event_crf import EventCrf, EventModelSpec
from seenerf.sensors.exposure import ExposureIntegral, blur_log_radiance
from seenerf.sensors.rgb_crf import PowerCrf, RgbCrf, apply_power_crf, apply_rgb_crf

__all__ = [
    "EventCrf",
    "EventModelSpec",
    "ExposureIntegral",
    "PowerCrf",
    "RgbCrf",
    "apply_power_crf",
    "apply_rgb_crf",
    "blur_log_radiance",
]
