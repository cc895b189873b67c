"""The driver against the emulated DAVIS346: discovery, versions, register sequences, closing."""

import time

import numpy as np
import pytest
import usb.core

from davis_io.errors import DeviceError
from davis_io.types import EVENT_DTYPE, ColorFilter, Packet
from davis_io.usb import ApsConfig, DavisConfig, DevicePermissionError, list_cameras, open_camera
from davis_io.usb.config import config_registers
from davis_io.usb.emulated import EmulatedBackend, EmulatedDavis346

# davis-protocol.md §2.7, dataStart step 1 and dataStop: (module, param) switched off in order.
ALL_OFF = [
    (1, 3, 0),
    (2, 4, 0),
    (3, 2, 0),
    (3, 3, 0),
    (3, 4, 0),
    (4, 0, 0),
    (0, 0, 0),
    (0, 1, 0),
    (9, 0, 0),
    (0, 3, 0),
]
# Steps 5-7: RUN_CHIP, then USB RUN, TIMESTAMP_RUN, MUX RUN, then the producers.
START_ON = [
    (0, 3, 1),
    (9, 0, 1),
    (0, 1, 1),
    (0, 0, 1),
    (1, 3, 1),
    (2, 4, 1),
    (3, 2, 1),
    (3, 3, 1),
    (3, 4, 1),
    (4, 0, 1),
]


def random_events(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    ev = np.zeros(n, EVENT_DTYPE)
    ev["t"] = np.sort(rng.integers(1_000_000, 1_300_000, n))
    ev["x"], ev["y"] = rng.integers(0, 346, n), rng.integers(0, 260, n)
    ev["p"] = rng.choice(np.array([-1, 1], np.int8), n)
    return ev


def test_listing_names_model_serial_versions_and_speed():
    backend = EmulatedBackend(
        EmulatedDavis346(serial="00000104"),
        EmulatedDavis346(serial="00000777", address=2, logic_version=17),
    )
    first, second = list_cameras(backend)
    assert (first.model, first.serial, first.firmware, first.logic) == (
        "DAVIS346",
        "00000104",
        6,
        "18.1",
    )
    assert first.usable and first.speed.startswith("super")
    assert not second.usable
    assert "logic version 17 found, exactly 18 needed" in second.problem


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"firmware": 5}, "firmware version 5 found, 6 or newer needed"),
        ({"logic_version": 19}, "logic version 19 found, exactly 18 needed"),
        ({"logic_patch": 0}, "logic patch 0 found, 1 or newer needed"),
    ],
)
def test_unsupported_versions_are_refused(options, message):
    device = EmulatedDavis346(**options)
    with pytest.raises(DeviceError, match=message):
        open_camera(backend=EmulatedBackend(device))
    assert not device.claimed


def test_several_cameras_need_a_serial():
    backend = EmulatedBackend(
        EmulatedDavis346(serial="AAA"), EmulatedDavis346(serial="BBB", address=2)
    )
    with pytest.raises(DeviceError, match=r"2 DAVIS cameras attached \(AAA, BBB\)"):
        open_camera(backend=backend)
    camera = open_camera("BBB", backend=backend)
    assert camera.info.serial == "BBB"
    camera.close()
    with pytest.raises(DeviceError, match="no DAVIS camera with serial 'CCC'"):
        open_camera("CCC", backend=backend)


def test_camera_held_by_another_program_is_named():
    (listing,) = list_cameras(EmulatedBackend(EmulatedDavis346(in_use_elsewhere=True)))
    assert not listing.usable and "in use by another program" in listing.problem


def test_no_camera_is_a_clear_error():
    with pytest.raises(DeviceError, match="no DAVIS camera found"):
        open_camera(backend=EmulatedBackend())


def test_permission_error_prints_the_sudo_line():
    with pytest.raises(DevicePermissionError, match="sudo .* udev --install"):
        open_camera(backend=EmulatedBackend(EmulatedDavis346(deny_access=True)))


def test_info_reads_the_colour_filter_and_sizes():
    camera = open_camera(backend=EmulatedBackend(EmulatedDavis346(color_filter=ColorFilter.RGGB)))
    camera.close()
    assert camera.info.color_filter is ColorFilter.RGGB
    assert (camera.info.camera, camera.info.width, camera.info.height) == ("DAVIS346", 346, 260)
    assert (camera.info.firmware_version, camera.info.logic_version) == (6, 18)


def test_start_and_stop_sequences_are_exactly_the_spec():
    device = EmulatedDavis346()
    camera = open_camera(backend=EmulatedBackend(device))
    with camera:
        configuration = config_registers(DavisConfig(), camera.facts)
        assert device.writes == configuration + ALL_OFF + START_ON
        assert device.clear_halt_count == 1
        assert {request.request for request in device.requests} == {0xBF}
        n_before_stop = len(device.writes)
    assert device.writes[n_before_stop:] == ALL_OFF
    assert not device.claimed and not camera.reader.running


def test_config_change_writes_only_what_changed():
    device = EmulatedDavis346()
    with open_camera(backend=EmulatedBackend(device)) as camera:
        before = len(device.requests)
        writes = camera.configure(DavisConfig(aps=ApsConfig(exposure_us=150_000)))
        # 150000 µs x 30 MHz ADC clock = 4500000 cycles, one single write, nothing else.
        assert writes == [(2, 12, 4_500_000)]
        assert [(r.request, r.writes) for r in device.requests[before:]] == [
            (0xBF, ((2, 12, 4_500_000),))
        ]
        # The recorded configuration follows, with the chip's default biases spelled out.
        assert camera.info.extra["config"]["aps"]["exposure_us"] == 150_000
        assert camera.info.extra["config"]["biases"]["on_bn"] == 0x5FFF
        before = len(device.requests)
        camera.timestamp_reset()
        assert [(r.request, r.writes) for r in device.requests[before:]] == [
            (0xC2, ((0, 2, 1), (0, 2, 0)))
        ]


def test_ctrl_c_inside_the_block_still_stops_and_releases(list_source):
    device = EmulatedDavis346(source=list_source([Packet(events=random_events(1000))]))
    camera = open_camera(backend=EmulatedBackend(device))
    with pytest.raises(KeyboardInterrupt), camera:
        raise KeyboardInterrupt
    assert device.writes[-10:] == ALL_OFF
    assert not device.claimed and not camera.reader.running


def test_close_after_unplug_releases_and_joins(list_source):
    device = EmulatedDavis346(source=list_source([Packet(events=random_events(1000))]))
    camera = open_camera(backend=EmulatedBackend(device))
    with camera:
        device.connected = False
    assert not device.claimed and not camera.reader.running
    with pytest.raises(usb.core.USBError):
        EmulatedBackend(device).open_device(device)


def test_slow_consumer_never_blocks_the_reader_and_losses_are_counted(list_source, drained):
    ev = random_events(300_000, seed=5)
    device = EmulatedDavis346(
        source=list_source([Packet(events=ev[i : i + 30_000]) for i in range(0, len(ev), 30_000)])
    )
    camera = open_camera(backend=EmulatedBackend(device), queue_packets=2, read_bytes=16384)
    received, reported = 0, 0
    with camera:
        for packet in camera:
            time.sleep(0.02)
            received += len(packet.events)
            reported += packet.dropped_events
            if drained(device, camera, packet):
                break
    assert camera.reader.stats.packets_lost > 0
    assert reported == camera.reader.stats.events_lost
    assert received + reported == len(ev)


def test_drop_counter_is_read_as_64_bits_and_skipped_without_statistics():
    device = EmulatedDavis346()
    # MUX 83 holds the upper 32 bits, 84 the lower: (2 << 32) + 5 events.
    device.registers[(0, 83)], device.registers[(0, 84)] = 2, 5
    camera = open_camera(backend=EmulatedBackend(device))
    assert camera.poll_drops() == (2 << 32) + 5
    assert camera.poll_drops() == 0
    camera.close()
    device.registers[(0, 80)] = 0
    camera = open_camera(backend=EmulatedBackend(device))
    assert camera.poll_drops() == 0
    camera.close()


def test_a_failing_source_ends_the_stream_with_a_typed_error():
    class Broken:
        info = None

        def __enter__(self):
            return self

        def __exit__(self, *exc_info):
            return None

        def __iter__(self):
            raise OSError("recording vanished")

    device = EmulatedDavis346(source=Broken())
    with (
        pytest.raises(DeviceError, match="recording vanished"),
        open_camera(backend=EmulatedBackend(device)) as camera,
    ):
        for _ in camera:
            pass
    assert not device.claimed and not camera.reader.running
