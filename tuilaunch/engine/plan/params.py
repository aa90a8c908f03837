"""The YAML parameter files handed to nodes (the typed values are in describe/values.py)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..describe.values import ParamValue
from ..errors import LaunchError


def write_parameter_file(path: Path, params: dict[str, ParamValue]) -> None:
    """A `--params-file` for one node; `/**` so the values apply whatever the node's name.

    Only the user can read it (0600), in a folder only the user can enter; it is created
    afresh (never through a symlink, never into someone else's file)."""
    import yaml

    _private_folder(path.parent)
    path.unlink(missing_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC,
                 0o600)
    with os.fdopen(fd, "w") as handle:
        yaml.safe_dump({"/**": {"ros__parameters": params}}, handle, default_flow_style=False,
                       sort_keys=False)


def _private_folder(folder: Path) -> None:
    try:
        folder.mkdir(mode=0o700, parents=True)
        return
    except FileExistsError:
        pass
    info = os.lstat(folder)
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.geteuid() or info.st_mode & 0o077:
        raise LaunchError(f"parameter folder {folder} is not a private folder of this user "
                          "(a symlink, another owner, or open to others): not writing there")
