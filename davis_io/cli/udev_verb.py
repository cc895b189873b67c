"""``seecap udev``: print the udev rule for DAVIS cameras, or install it with ``--install``."""

from __future__ import annotations

import argparse

from davis_io.usb.udev import install_rules, rules_text

__all__ = ["HELP", "add_arguments", "run"]

HELP = "print the udev rule giving the logged-in user access to DAVIS cameras (--install: as root)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """``--install``."""
    parser.add_argument(
        "--install",
        action="store_true",
        help="write the rule to /etc/udev/rules.d and reload udev (needs root)",
    )


def run(args: argparse.Namespace) -> int:
    """Print the rule, or install it and print the commands run."""
    if not args.install:
        print(rules_text(), end="")
        return 0
    for command in install_rules():
        print("ran: " + " ".join(command))
    print("installed; re-plug the camera")
    return 0
