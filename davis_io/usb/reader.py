"""The bulk-IN reader thread: reads, decodes and queues packets, never waiting on the consumer."""

from __future__ import annotations

import queue
import threading
from dataclasses import dataclass

import usb.core
import usb.util

from davis_io.errors import DeviceError
from davis_io.types import Packet
from davis_io.usb.control import device_error
from davis_io.usb.layout import SensorLayout
from davis_io.usb.protocol import BULK_IN_ENDPOINT
from davis_io.usb.words import WordDecoder

__all__ = ["QueueStats", "StreamReader"]

_READ_TIMEOUT_MS = 100


@dataclass
class QueueStats:
    """Host-side losses: packets the consumer was too slow to take (never waited for).

    Attributes:
        packets_lost: packets dropped because the queue was full.
        events_lost: DVS events in those packets.
        frames_lost: frames in those packets.
        transfers: bulk transfers read and decoded.
        bytes: bytes read and decoded (their packets are queued or counted as lost).
    """

    packets_lost: int = 0
    events_lost: int = 0
    frames_lost: int = 0
    transfers: int = 0
    bytes: int = 0


class StreamReader:
    """Reads bulk IN 0x82 in a thread, decodes each transfer and queues the packet.

    A full queue drops the packet (counted, and reported in the next packet the consumer gets);
    a USB error ends the thread and is raised by :meth:`next_packet` once the queue is empty.
    """

    def __init__(
        self, device: usb.core.Device, layout: SensorLayout, queue_packets: int, read_bytes: int
    ):
        self.device = device
        self.decoder = WordDecoder(layout)
        self.stats = QueueStats()
        self._queue: queue.Queue[Packet] = queue.Queue(maxsize=queue_packets)
        self._buffer = usb.util.create_buffer(read_bytes)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._error: DeviceError | None = None
        self._losses_lock = threading.Lock()
        self._unreported = (0, 0)

    def start(self) -> None:
        """Start the thread (once)."""
        self._thread = threading.Thread(target=self._run, name="davis-usb-reader", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Ask the thread to end and wait for it."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()

    @property
    def running(self) -> bool:
        """True while the thread reads."""
        return self._thread is not None and self._thread.is_alive()

    def _run(self) -> None:
        try:
            self._read_until_stopped()
        except usb.core.USBError as error:
            self._error = device_error(error, "reading the event stream")
        except Exception as error:  # any failure goes to the consumer thread, never lost
            self._error = DeviceError(f"reading the event stream failed: {error!r}")
            self._error.__cause__ = error

    def _read_until_stopped(self) -> None:
        while not self._stop.is_set():
            try:
                count = self.device.read(BULK_IN_ENDPOINT, self._buffer, _READ_TIMEOUT_MS)
            except usb.core.USBTimeoutError:
                continue
            packet = self.decoder.decode(memoryview(self._buffer)[:count])
            if not packet.is_empty or packet.notes:
                self._offer(packet)
            self.stats.transfers += 1
            self.stats.bytes += count

    def _offer(self, packet: Packet) -> None:
        try:
            self._queue.put_nowait(packet)
        except queue.Full:
            self.stats.packets_lost += 1
            self.stats.events_lost += len(packet.events)
            self.stats.frames_lost += len(packet.frames)
            with self._losses_lock:
                events, frames = self._unreported
                self._unreported = (events + len(packet.events), frames + len(packet.frames))

    def _report_losses(self, packet: Packet) -> Packet:
        with self._losses_lock:
            (events, frames), self._unreported = self._unreported, (0, 0)
        if events or frames:
            packet.dropped_events += events
            packet.notes.append(f"host queue full: {events} events and {frames} frames lost")
        return packet

    @property
    def pending_packets(self) -> int:
        """Packets waiting in the queue."""
        return self._queue.qsize()

    def next_packet(self, idle_s: float) -> Packet | None:
        """The next packet; an empty one after ``idle_s`` without data; None once stopped.

        Raises:
            DeviceError: the stream ended with a USB error (after every queued packet).
        """
        try:
            return self._report_losses(self._queue.get(timeout=idle_s))
        except queue.Empty:
            if self._error is not None and not self.running:
                raise self._error from None
            if self._stop.is_set():
                return None
            return self._report_losses(Packet())
