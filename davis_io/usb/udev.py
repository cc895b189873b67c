"""The udev rule granting the logged-in user access to DAVIS cameras, and its installation."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

from davis_io.errors import DavisIOError

__all__ = [
    "RULES_DIR",
    "RULES_NAME",
    "SHIPPED_RULES",
    "install_hint",
    "install_rules",
    "installed_rule_path",
    "rules_text",
]

RULES_NAME = "60-seecap-davis.rules"
RULES_DIR = Path("/etc/udev/rules.d")
SHIPPED_RULES = Path(__file__).resolve().with_name(RULES_NAME)
"""The rule file shipped inside the package (package data; the repository's ``udev/`` folder holds
the same file for installation without Python)."""


def rules_text() -> str:
    """Text of the shipped rule file (vendor 152a, products 841a and 841b, uaccess)."""
    try:
        return SHIPPED_RULES.read_text(encoding="utf-8")
    except OSError as error:
        raise DavisIOError(
            f"cannot read the udev rule file {SHIPPED_RULES}: {error}; reinstall seecap"
        ) from error


def installed_rule_path(rules_dir: Path = RULES_DIR) -> Path | None:
    """Path of an installed copy of the rule whose text matches ours, else None."""
    path = rules_dir / RULES_NAME
    try:
        return path if path.read_text(encoding="utf-8") == rules_text() else None
    except OSError:
        return None


def install_hint() -> str:
    """The exact command a non-root user runs to install the rule."""
    command = [sys.executable, "-m", "davis_io.cli", "udev", "--install"]
    return "sudo " + shlex.join(command)


def install_rules(rules_dir: Path = RULES_DIR, *, run=subprocess.run) -> list[list[str]]:
    """Write the rule file and reload udev (root only).

    Args:
        rules_dir: where udev reads rules from.
        run: how commands are run (argument lists, never a shell).

    Returns:
        The commands that were run.

    Raises:
        DavisIOError: not root (the message gives the sudo line), or a command failed.
    """
    if os.geteuid() != 0:
        raise DavisIOError(f"installing udev rules needs root; run:\n  {install_hint()}")
    target = rules_dir / RULES_NAME
    try:
        target.write_text(rules_text(), encoding="utf-8")
    except OSError as error:
        raise DavisIOError(
            f"cannot write {target}: {error.strerror}; is udev installed?"
        ) from error
    commands = [
        ["udevadm", "control", "--reload-rules"],
        ["udevadm", "trigger", "--subsystem-match=usb", "--attr-match=idVendor=152a"],
    ]
    for command in commands:
        try:
            result = run(command, check=False, capture_output=True, text=True)
        except OSError as error:
            raise DavisIOError(
                f"cannot run {command[0]}: {error.strerror}; is udev installed?"
            ) from error
        if result.returncode != 0:
            raise DavisIOError(
                f"{shlex.join(command)} failed ({result.returncode}): "
                f"{result.stderr.strip()}; re-plug the camera after fixing udev"
            )
    return commands
