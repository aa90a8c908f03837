"""The ament index lookups, now in `tuilaunch.engine.packages` (below describe, which needs
them too); names re-exported for callers in run/ and the CLI that still import them here."""

from ..packages import (
    ensure_environment,
    environment_prefixes,
    find_executable,
    find_in_share,
    find_launch_file_in_share,
    known_packages,
    package_prefix,
    package_share,
)

__all__ = ["ensure_environment", "environment_prefixes", "find_executable", "find_in_share",
           "find_launch_file_in_share", "known_packages", "package_prefix", "package_share"]
