"""System packages some tests need (openssh-server, gdb, zsh, tmux): installed with apt-get
where the tests run as root and it is there, as the README says; the tests skip, saying so,
otherwise."""

from __future__ import annotations

import os
import shutil
import subprocess


def apt_install(package: str) -> bool:
    """Installs a Debian package if we may; True when the install command succeeded. A
    machine whose package lists were never fetched gets them first."""
    if os.geteuid() != 0 or not shutil.which("apt-get"):
        return False
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}

    def install() -> bool:
        return subprocess.run(["apt-get", "install", "-y", "-qq", package],
                              capture_output=True, timeout=600, env=env).returncode == 0

    if install():
        return True
    subprocess.run(["apt-get", "update", "-qq"], capture_output=True, timeout=600, env=env)
    return install()


def program(name: str, package: str | None = None) -> str | None:
    """The path of `name`, installing `package` (default: `name`) first where it is missing
    and we may; None when it is not there after all."""
    return shutil.which(name) or (apt_install(package or name) and shutil.which(name)) or None
