"""Real OpenSSH servers on 127.0.0.1 for the tests of sessions on other machines.

Each `Machine` is one `sshd -D` on a free port with a temporary host key, accepting one
temporary client key. Its sessions run with their own `XDG_RUNTIME_DIR` (set by the server's
`SetEnv`), so "robot1"'s sessions never mix with the test's local ones or with robot2's. The
login shell gets the test's venv and code (PATH, PYTHONPATH) and ROS_DOMAIN_ID, as a robot
set up with the same tuilaunch would.

`ssh -F machines.ssh_config robot1 ...` reaches it; `TUILAUNCH_SSH_COMMAND` is set to that.
At teardown every process started under a machine (found by its runtime folder in its
environment, or as a descendant of its sshd) is ended: nothing outlives the test.

Use: `from .sshd import machines_fixture  # noqa: F401` in a test module, then the
`machines` fixture.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from .proc_tree import alive, descendants, end, environ, pids, terminate
from .system_packages import apt_install

SSHD = "/usr/sbin/sshd"
PRIVSEP_DIR = "/run/sshd"
ROOT = Path(__file__).resolve().parents[2]
REMOTE = f"{shlex.quote(sys.executable)} -m tuilaunch"
"""The remote tuilaunch: the test's venv and code, as `tuilaunch` would be on a robot."""


def ensure_sshd() -> None:
    """sshd is needed; where it is missing and we may, install it once, else skip."""
    if not os.access(SSHD, os.X_OK):
        apt_install("openssh-server")
    if not os.access(SSHD, os.X_OK):
        pytest.skip(f"{SSHD} is not installed (apt-get install openssh-server)")
    if not shutil.which("ssh") or not shutil.which("ssh-keygen"):
        pytest.skip("the OpenSSH client (ssh, ssh-keygen) is not installed")
    if os.geteuid() == 0 and not os.path.isdir(PRIVSEP_DIR):
        # sshd refuses to start without its privilege separation folder (made by the
        # package's service unit, which does not run in a container)
        os.makedirs(PRIVSEP_DIR, mode=0o755, exist_ok=True)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def keygen(path: Path) -> None:
    subprocess.run(["ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", str(path)],
                   check=True, capture_output=True)


class Machine:
    """One sshd: a "machine" named `alias` in the client config."""

    def __init__(self, alias: str, folder: Path, authorized: Path) -> None:
        self.alias = alias
        self.folder = folder
        folder.mkdir(parents=True)
        # short: a session socket path must fit in 108 bytes
        self.runtime = Path(tempfile.mkdtemp(prefix=f"tl{alias}"))
        os.chmod(self.runtime, 0o700)
        self.port = free_port()
        host_key = folder / "host_key"
        keygen(host_key)
        environment = {
            "XDG_RUNTIME_DIR": str(self.runtime),
            "PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin",
            "PYTHONPATH": str(ROOT),
            "ROS_DOMAIN_ID": os.environ.get("ROS_DOMAIN_ID", "0"),
            "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
            "ROS_LOG_DIR": str(folder / "roslog"),
        }
        set_env = " ".join(f'"{k}={v}"' for k, v in environment.items())
        self.config = folder / "sshd_config"
        self.config.write_text(
            f"Port {self.port}\n"
            "ListenAddress 127.0.0.1\n"
            f"HostKey {host_key}\n"
            f"PidFile {folder / 'sshd.pid'}\n"
            f"AuthorizedKeysFile {authorized}\n"
            "StrictModes no\n"
            "UsePAM no\n"
            "PasswordAuthentication no\n"
            "KbdInteractiveAuthentication no\n"
            "PubkeyAuthentication yes\n"
            "PermitRootLogin prohibit-password\n"
            "PrintMotd no\n"
            "LogLevel ERROR\n"
            f"SetEnv {set_env}\n")
        self.log = folder / "sshd.log"
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen([SSHD, "-D", "-e", "-f", str(self.config)],
                                         stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                                         start_new_session=True)
        deadline = time.monotonic() + 30
        while not self._listening():
            if self.proc.poll() is not None:
                shutil.rmtree(self.runtime, ignore_errors=True)
                raise RuntimeError(f"sshd for {alias} ended: {self.log.read_text()}")
            assert time.monotonic() < deadline, f"sshd for {alias} never listened"
            time.sleep(0.05)

    def _listening(self) -> bool:
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=1):
                return True
        except OSError:
            return False

    def server_pid(self, name: str) -> int:
        """The pid of the server of session `name` here, as the info it wrote says (what
        `tuilaunch status NAME` there says, without a command to run)."""
        info = self.runtime / "tuilaunch" / f"{name}.json"
        return int(json.loads(info.read_text())["pid"])

    def stop(self) -> None:
        """Ends what runs under this machine (sessions first, which stop their nodes), then
        its sshd."""
        marker = f"XDG_RUNTIME_DIR={self.runtime}".encode()
        under = [pid for pid in pids() if marker in environ(pid).split(b"\0")]
        under += descendants(self.proc.pid)
        end(under)
        terminate(self.proc)
        end(descendants(self.proc.pid))
        shutil.rmtree(self.runtime, ignore_errors=True)


class Machines:
    """Several sshd "machines" and one ssh client config naming them."""

    def __init__(self, folder: Path, aliases: tuple[str, ...] = ("robot1", "robot2")) -> None:
        ensure_sshd()
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)
        self.client_key = folder / "client_key"
        keygen(self.client_key)
        self.authorized = folder / "authorized_keys"
        shutil.copy(self.client_key.with_suffix(".pub"), self.authorized)
        self.machines: dict[str, Machine] = {}
        try:
            for alias in aliases:
                self.machines[alias] = Machine(alias, folder / alias, self.authorized)
        except BaseException:
            self.stop()
            raise
        self.ssh_config = folder / "ssh_config"
        self.ssh_config.write_text("".join(self.host_entry(alias, m.port)
                                           for alias, m in self.machines.items()))
        self.ssh_command = f"ssh -F {shlex.quote(str(self.ssh_config))}"

    def host_entry(self, alias: str, port: int, key: Path | None = None) -> str:
        return (f"Host {alias}\n"
                "  HostName 127.0.0.1\n"
                f"  Port {port}\n"
                f"  IdentityFile {key or self.client_key}\n"
                "  IdentitiesOnly yes\n"
                "  UserKnownHostsFile /dev/null\n"
                "  StrictHostKeyChecking no\n"
                "  BatchMode yes\n"
                "  LogLevel ERROR\n")

    def __getitem__(self, alias: str) -> Machine:
        return self.machines[alias]

    def env(self, **extra: str) -> dict[str, str]:
        """What a client on "the laptop" needs to reach the machines."""
        return {"TUILAUNCH_SSH_COMMAND": self.ssh_command, "TUILAUNCH_REMOTE": REMOTE, **extra}

    def stop(self) -> None:
        for machine in self.machines.values():
            machine.stop()


@pytest.fixture(name="machines")
def machines_fixture(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Machines]:
    """robot1 and robot2, reachable through `TUILAUNCH_SSH_COMMAND` (set for the test)."""
    fleet = Machines(tmp_path / "ssh")
    for key, value in fleet.env().items():
        monkeypatch.setenv(key, value)
    try:
        yield fleet
    finally:
        fleet.stop()


def proxies_on(machine: Machine) -> list[int]:
    """The `__proxy` processes under `machine` (the far end of each ssh link)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
            environ = (entry / "environ").read_bytes()
        except OSError:
            continue
        if b"__proxy" in argv and str(machine.runtime).encode() in environ:
            found.append(int(entry.name))
    return [pid for pid in found if alive(pid)]


__all__ = ["Machine", "Machines", "alive", "free_port", "keygen", "machines_fixture",
           "proxies_on"]
