"""A started process as one shell line: its exact argv, working directory and the changes to
the launcher's environment, ready to paste into a shell to run it by hand."""

from __future__ import annotations

import shlex
from collections.abc import Mapping


def env_changes(base: Mapping[str, str], final: Mapping[str, str]
                ) -> tuple[dict[str, str], list[str]]:
    """What `final` sets (new or different values) and unsets, relative to `base`."""
    changed = {k: v for k, v in final.items() if base.get(k) != v}
    removed = sorted(k for k in base if k not in final)
    return changed, removed


def shell_command(cmd: list[str], env: Mapping[str, str] | None = None,
                  cwd: str | None = None, *, unset: list[str] | None = None,
                  clear_env: bool = False) -> str:
    """`cd DIR && env -u GONE -- NAME=value prog 'arg with spaces'`, every word quoted.

    `env` holds what the process gets on top of the launcher's environment (all of it when
    `clear_env`: `env -i`, as a launch `env=` starts from nothing); `unset` what it lost.
    """
    words: list[str] = []
    if clear_env or env or unset:
        words.append("env")
        if clear_env:
            words.append("-i")
        for name in unset or []:
            words += ["-u", name]
        words.append("--")  # ends env's options; assignments, then the command, follow
        words += [f"{name}={value}" for name, value in sorted((env or {}).items())]
    line = shlex.join(words + cmd)
    return f"cd {shlex.quote(cwd)} && {line}" if cwd else line
