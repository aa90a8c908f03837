"""The YAML parameter files handed to nodes (the typed values are in describe/values.py), and
the private folder of each tuilaunch process they are written in."""

from __future__ import annotations

import atexit
import os
import re
import shutil
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


_params_dir: Path | None = None


def default_params_dir() -> Path:
    """One private folder per tuilaunch process (mkdtemp: 0700, a name nobody can guess)."""
    global _params_dir
    # made anew when a finished run removed it (a launcher may plan several runs)
    if _params_dir is None or not _params_dir.is_dir():
        # on the first plan: every plan has its folder (made before any file is written),
        # the commands that plan nothing (ls, stop, logs...) do not import tempfile
        import tempfile

        _params_dir = Path(tempfile.mkdtemp(prefix=f"tuilaunch-{os.getpid()}-params-"))
        atexit.register(shutil.rmtree, _params_dir, True)
        remove_stale_params_dirs(_params_dir.parent)
    return _params_dir


_PARAMS_DIR_NAME = re.compile(r"^tuilaunch-(\d+)-params-")


def remove_stale_params_dirs(folder: Path) -> None:
    """The folders of tuilaunch processes that died without their atexit (a session
    server killed with SIGKILL) are removed by the next one that plans: ours, named after
    a pid that no longer runs."""
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        match = _PARAMS_DIR_NAME.match(entry.name)
        if match is None or not entry.is_dir(follow_symlinks=False):
            continue
        try:
            if entry.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            with open(f"/proc/{int(match.group(1))}/stat", "rb") as stat:
                state = stat.read().rsplit(b")", 1)[1].split()[0]
        except FileNotFoundError:
            state = b"X"  # no such process
        except (OSError, IndexError):
            continue
        if state in (b"X", b"Z"):  # gone, or a zombie nobody reaped yet
            shutil.rmtree(entry.path, True)


def remove_default_params_dir() -> None:
    """What the atexit hook does, for a process that leaves with os._exit (a TUI whose
    terminal hung up cannot run Textual's teardown), so no folder is left in $TMPDIR."""
    global _params_dir
    if _params_dir is not None:
        shutil.rmtree(_params_dir, True)
        _params_dir = None
