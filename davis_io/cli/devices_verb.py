"""``seecap devices``: list attached DAVIS cameras and whether each can be opened."""

from __future__ import annotations

import argparse

from davis_io.usb.discovery import list_cameras

__all__ = ["HELP", "add_arguments", "run"]

HELP = "list attached DAVIS cameras: model, serial, firmware, logic, USB speed, usable or why not"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """No options."""


def run(args: argparse.Namespace) -> int:
    """Print one block per camera; exit 1 when none is attached."""
    cameras = list_cameras()
    if not cameras:
        print("no DAVIS camera found (USB 152a:841a or 152a:841b); try `seecap doctor`")
        return 1
    for camera in cameras:
        state = "usable" if camera.usable else f"NOT usable: {camera.problem}"
        print(
            f"{camera.model}  serial {camera.serial or '?'}  firmware {camera.firmware}  "
            f"logic {camera.logic or '?'}  USB {camera.speed}  "
            f"bus {camera.bus} address {camera.address}\n  {state}"
        )
    return 0
