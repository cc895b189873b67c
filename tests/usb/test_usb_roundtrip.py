"""The real recording through encoder, emulated USB and driver, with and without faults."""

from dataclasses import dataclass, field

import numpy as np
import pytest

from davis_io.aedat import open_recording
from davis_io.errors import DeviceError
from davis_io.types import TriggerKind
from davis_io.usb import DeviceDisconnected, DeviceStalled, open_camera
from davis_io.usb.emulated import EmulatedBackend, EmulatedDavis346, StreamFaults

# Fixture facts (tests/fixtures/README.md): frame 2 reads out 1633953691007091..1633953691030743.
RESET_IN_FRAME_2 = 1633953691010000
DROP_WINDOW = (1633953691000000, 1633953691003000)


@dataclass
class Run:
    events: list = field(default_factory=list)
    frames: list = field(default_factory=list)
    imu: list = field(default_factory=list)
    triggers: list = field(default_factory=list)
    dropped: int = 0
    notes: list = field(default_factory=list)
    error: DeviceError | None = None


@pytest.fixture
def aestream_aedat4_path(aestream_aedat4):
    return aestream_aedat4


@pytest.fixture
def fixture_packets(aestream_aedat4):
    with open_recording(aestream_aedat4) as recording:
        packets = list(recording)
    return {
        "events": np.concatenate([p.events for p in packets]),
        "frames": [f for p in packets for f in p.frames],
        "imu": np.concatenate([p.imu for p in packets]),
    }


def stream(path, faults: StreamFaults, drained) -> tuple[Run, EmulatedDavis346]:
    device = EmulatedDavis346(source=open_recording(path), faults=faults, record_delivered=True)
    run = Run()
    try:
        with open_camera(backend=EmulatedBackend(device)) as camera:
            for packet in camera:
                run.events.append(packet.events)
                run.frames += packet.frames
                run.imu.append(packet.imu)
                run.triggers.append(packet.triggers)
                run.dropped += packet.dropped_events
                run.notes += packet.notes
                if drained(device, camera, packet):
                    break
    except DeviceError as error:
        run.error = error
    origin = device.time_origin_us
    run.events = np.concatenate(run.events)
    run.events["t"] += origin
    run.imu = np.concatenate(run.imu)
    run.imu["t"] += origin
    run.triggers = np.concatenate(run.triggers)
    run.triggers["t"] += origin
    run.frames = [(f, origin) for f in run.frames]
    run.stats = camera.reader.decoder.stats
    return run, device


def assert_same_frames(decoded, expected):
    assert len(decoded) == len(expected)
    for (frame, origin), source in zip(decoded, expected, strict=True):
        # 8-bit source value v was sent as 10-bit v << 2; DV's 8 bits are the 10-bit value >> 2.
        assert frame.bit_depth == 10 and source.bit_depth == 8
        assert np.array_equal(frame.image, source.image.astype(np.uint16) << 2)
        assert np.array_equal(frame.image >> 2, source.image)
        assert (
            frame.readout_start_us + origin,
            frame.exposure_start_us + origin,
            frame.exposure_end_us + origin,
            frame.readout_end_us + origin,
        ) == (
            source.readout_start_us,
            source.exposure_start_us,
            source.exposure_end_us,
            source.readout_end_us,
        )


def column_words_delivered(device: EmulatedDavis346) -> int:
    """Events whose words reached the host, counted on the raw bytes (codes 2 and 3)."""
    data = bytes(device.delivered)
    words = np.frombuffer(data[: len(data) & ~1], dtype="<u2")
    return int(np.count_nonzero((words >> 13) == 1))


def test_clean_round_trip_is_exact(aestream_aedat4_path, fixture_packets, drained):
    run, _ = stream(aestream_aedat4_path, StreamFaults(), drained)
    assert run.error is None and run.dropped == 0
    assert np.array_equal(run.events, fixture_packets["events"])  # t, x, y, p
    assert_same_frames(run.frames, fixture_packets["frames"])
    np.testing.assert_array_equal(run.imu["t"], fixture_packets["imu"]["t"])
    np.testing.assert_allclose(run.imu["acc_g"], fixture_packets["imu"]["acc_g"], atol=1e-6)
    np.testing.assert_allclose(run.imu["gyro_dps"], fixture_packets["imu"]["gyro_dps"], atol=1e-5)
    np.testing.assert_allclose(
        run.imu["temperature_c"], fixture_packets["imu"]["temperature_c"], atol=1e-4
    )
    expected = [
        (f.readout_start_us, TriggerKind.APS_FRAME_START) for f in fixture_packets["frames"]
    ]
    decoded = run.triggers[run.triggers["kind"] == TriggerKind.APS_FRAME_START]
    assert decoded.tolist() == expected


@pytest.mark.parametrize(
    "faults",
    [
        StreamFaults(split_transfers=True),
        StreamFaults(device_start_us=2**31 - 250_000),
    ],
    ids=["split-words", "31-bit-wrap"],
)
def test_lossless_faults_change_nothing(aestream_aedat4_path, fixture_packets, drained, faults):
    run, _ = stream(aestream_aedat4_path, faults, drained)
    assert np.array_equal(run.events, fixture_packets["events"])
    assert_same_frames(run.frames, fixture_packets["frames"])
    if faults.split_transfers:
        assert run.stats.split_words > 0
    else:
        device_t = run.events["t"] - run.frames[0][1]  # back to device time
        assert device_t[0] < 2**31 < device_t[-1]


def test_timestamp_reset_keeps_events_and_drops_the_cut_frame(
    aestream_aedat4_path, fixture_packets, drained
):
    run, _ = stream(aestream_aedat4_path, StreamFaults(reset_at_us=(RESET_IN_FRAME_2,)), drained)
    assert np.array_equal(run.events, fixture_packets["events"])
    frames = fixture_packets["frames"]
    assert_same_frames(run.frames, [frames[0], frames[2]])
    assert run.stats.frames_dropped == 1 and run.stats.timestamp_resets == 2
    assert any("timestamp reset" in note for note in run.notes)
    resets = run.triggers[run.triggers["kind"] == TriggerKind.TIMESTAMP_RESET]["t"]
    assert resets.tolist()[-1] == RESET_IN_FRAME_2


def test_device_drops_are_reported_exactly(aestream_aedat4_path, fixture_packets, drained):
    faults = StreamFaults(drop_event_windows_us=(DROP_WINDOW,))
    run, _ = stream(aestream_aedat4_path, faults, drained)
    t = fixture_packets["events"]["t"]
    inside = (t >= DROP_WINDOW[0]) & (t < DROP_WINDOW[1])
    assert np.count_nonzero(inside) > 1000
    assert np.array_equal(run.events, fixture_packets["events"][~inside])
    assert run.dropped == np.count_nonzero(inside)
    assert_same_frames(run.frames, fixture_packets["frames"])


@pytest.mark.parametrize(
    ("faults", "error"),
    [
        (StreamFaults(stall_after_bytes=700_001), DeviceStalled),
        (StreamFaults(disconnect_after_bytes=900_001), DeviceDisconnected),
    ],
    ids=["stall", "disconnect"],
)
def test_stall_and_unplug_end_with_a_typed_error_after_all_complete_data(
    aestream_aedat4_path, fixture_packets, drained, faults, error
):
    run, device = stream(aestream_aedat4_path, faults, drained)
    assert isinstance(run.error, error)
    delivered = column_words_delivered(device)
    assert 0 < delivered < len(fixture_packets["events"])
    assert np.array_equal(run.events, fixture_packets["events"][:delivered])
    assert_same_frames(run.frames, fixture_packets["frames"][: len(run.frames)])
    assert not device.claimed


def test_every_fault_at_once(aestream_aedat4_path, fixture_packets, drained):
    faults = StreamFaults(
        split_transfers=True,
        device_start_us=2**31 - 250_000,
        reset_at_us=(RESET_IN_FRAME_2,),
        drop_event_windows_us=(DROP_WINDOW,),
        disconnect_after_bytes=1_400_001,
    )
    run, device = stream(aestream_aedat4_path, faults, drained)
    assert isinstance(run.error, DeviceDisconnected)
    t = fixture_packets["events"]["t"]
    inside = (t >= DROP_WINDOW[0]) & (t < DROP_WINDOW[1])
    kept = fixture_packets["events"][~inside]
    delivered = column_words_delivered(device)
    assert np.array_equal(run.events, kept[:delivered])
    frames = fixture_packets["frames"]
    assert_same_frames(run.frames, [frames[0], frames[2]][: len(run.frames)])
    assert run.dropped == np.count_nonzero(inside)
    assert run.stats.frames_dropped == 1 and run.stats.split_words > 0
