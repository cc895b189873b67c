"""Checks on a real DAVIS346 (opt-in: ``pytest -m hardware``); skipped without a camera."""

import time

import numpy as np
import pytest

from davis_io.errors import DeviceError
from davis_io.usb import ApsConfig, DavisConfig, list_cameras, open_camera

pytestmark = pytest.mark.hardware


@pytest.fixture
def camera_serial() -> str:
    try:
        cameras = [camera for camera in list_cameras() if camera.usable]
    except DeviceError as error:
        pytest.skip(f"no USB access: {error}")
    if not cameras:
        pytest.skip("no usable DAVIS camera attached")
    return cameras[0].serial


def collect(camera, seconds: float):
    events, frames, dropped = [], [], 0
    end = time.monotonic() + seconds
    for packet in camera:
        events.append(packet.events)
        frames += packet.frames
        dropped += packet.dropped_events
        if time.monotonic() > end:
            break
    return np.concatenate(events), frames, dropped


def test_stream_has_valid_events_and_frames(camera_serial):
    config = DavisConfig(aps=ApsConfig(exposure_us=10_000, frame_interval_us=50_000))
    with open_camera(camera_serial, config) as camera:
        events, frames, _ = collect(camera, 2.0)
        info = camera.info
    assert len(frames) >= 10
    assert np.all(np.diff(events["t"]) >= 0)
    assert events["x"].max() < info.width and events["y"].max() < info.height
    for frame in frames:
        assert frame.image.shape == (info.height, info.width)
        assert frame.readout_start_us <= frame.exposure_start_us <= frame.exposure_end_us
        assert frame.exposure_end_us <= frame.readout_end_us
        assert abs(frame.exposure_us - 10_000) <= 100


def test_exposure_change_while_streaming(camera_serial):
    with open_camera(camera_serial) as camera:
        camera.configure(DavisConfig(aps=ApsConfig(exposure_us=2_000)))
        collect(camera, 0.5)
        _, frames, _ = collect(camera, 1.0)
    assert frames and all(abs(frame.exposure_us - 2_000) <= 100 for frame in frames)
