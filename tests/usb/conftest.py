"""Helpers of the USB tests: a packet source over a list, and the end-of-stream condition."""

import pytest


class ListSource:
    """A minimal packet source over a list of packets."""

    info = None

    def __init__(self, packets):
        self.packets = packets

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        return None

    def __iter__(self):
        return iter(self.packets)


def _drained(device, camera, packet) -> bool:
    """True once the emulated device sent everything and the consumer got every packet of it."""
    return (
        device.exhausted
        and packet.is_empty
        and not camera.reader.pending_packets
        and camera.reader.stats.bytes == device.bytes_delivered
    )


@pytest.fixture
def list_source():
    return ListSource


@pytest.fixture
def drained():
    return _drained
