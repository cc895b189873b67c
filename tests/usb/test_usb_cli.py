"""``seecap udev``, ``seecap devices`` and ``seecap doctor`` against the emulated camera."""

import subprocess
import sys
from pathlib import Path

import pytest

from davis_io.cli import main
from davis_io.usb import discovery, doctor, udev
from davis_io.usb.emulated import EmulatedBackend, EmulatedDavis346


def test_udev_prints_the_rule_file(capsys):
    assert main(["udev"]) == 0
    text = capsys.readouterr().out
    assert text == udev.SHIPPED_RULES.read_text()
    rules = [line for line in text.splitlines() if line and not line.startswith("#")]
    assert rules == [
        'SUBSYSTEM=="usb", ATTR{idVendor}=="152a", ATTR{idProduct}=="841a", TAG+="uaccess"',
        'SUBSYSTEM=="usb", ATTR{idVendor}=="152a", ATTR{idProduct}=="841b", TAG+="uaccess"',
    ]
    assert "MODE" not in "".join(rules)


def test_packaged_rule_file_is_the_repository_copy():
    # The wheel ships davis_io/usb/60-seecap-davis.rules; udev/ at the top holds the same bytes.
    repository_copy = Path(__file__).resolve().parents[2] / "udev" / udev.RULES_NAME
    assert udev.SHIPPED_RULES.parent == Path(udev.__file__).resolve().parent
    assert udev.SHIPPED_RULES.read_bytes() == repository_copy.read_bytes()


def test_install_as_user_prints_the_exact_sudo_line(monkeypatch, capsys):
    monkeypatch.setattr(udev.os, "geteuid", lambda: 1000)
    assert main(["udev", "--install"]) == 1
    err = capsys.readouterr().err
    assert f"sudo {sys.executable} -m davis_io.cli udev --install" in err


def test_install_as_root_writes_and_reloads_with_argument_lists(monkeypatch, tmp_path):
    monkeypatch.setattr(udev.os, "geteuid", lambda: 0)
    calls = []

    def run(command, **kwargs):
        calls.append((command, kwargs))
        return subprocess.CompletedProcess(command, 0, "", "")

    commands = udev.install_rules(tmp_path, run=run)
    assert (tmp_path / udev.RULES_NAME).read_text() == udev.rules_text()
    assert [c for c, _ in calls] == commands
    assert commands[0] == ["udevadm", "control", "--reload-rules"]
    assert all(isinstance(c, list) and "shell" not in kw for c, kw in calls)
    assert udev.installed_rule_path(tmp_path) == tmp_path / udev.RULES_NAME


def test_install_reports_a_failing_udevadm(monkeypatch, tmp_path):
    monkeypatch.setattr(udev.os, "geteuid", lambda: 0)

    def run(command, **kwargs):
        return subprocess.CompletedProcess(command, 1, "", "no udev daemon")

    with pytest.raises(udev.DavisIOError, match="no udev daemon"):
        udev.install_rules(tmp_path, run=run)


@pytest.fixture
def emulated(monkeypatch):
    backend = EmulatedBackend()
    monkeypatch.setattr(discovery, "default_backend", lambda: backend)
    monkeypatch.setattr(doctor, "default_backend", lambda: backend)
    return backend


def test_devices_lists_each_camera(emulated, capsys):
    emulated.devices += [
        EmulatedDavis346(serial="00000104"),
        EmulatedDavis346(serial="00000200", address=2, firmware=5),
    ]
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "DAVIS346  serial 00000104  firmware 6  logic 18.1  USB super" in out
    assert "NOT usable: DAVIS FX3 board, serial 00000200: firmware version 5 found" in out


def test_devices_without_camera(emulated, capsys):
    assert main(["devices"]) == 1
    assert "no DAVIS camera found" in capsys.readouterr().out


def test_doctor_reports_a_permission_problem_with_the_fix(emulated, capsys, tmp_path):
    emulated.devices.append(EmulatedDavis346(deny_access=True))
    assert main(["doctor", "--path", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "[FAIL] camera" in out and "udev --install" in out
    assert "[ok] pycolmap" in out and "GiB free" in out


def test_doctor_does_not_import_torch():
    code = (
        "import sys; from davis_io.usb.doctor import run_checks; run_checks(); "
        "print('torch' in sys.modules)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert result.stdout.strip() == "False"
