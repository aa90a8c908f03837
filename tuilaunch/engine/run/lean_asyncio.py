"""asyncio without its TLS half, for the processes that run a launch.

asyncio imports `ssl` at once for TLS streams, which tuilaunch never opens (a remote link
is ssh, a child process). `ssl` maps OpenSSL's libcrypto: about 4 MB of every launcher's
and session server's memory, more than the rest of the event loop. Called before anything
imports asyncio, it imports asyncio with `ssl` hidden, so asyncio leaves TLS out; `ssl` is
then put back, and `import ssl` works as ever for whatever wants it later (a launch file).
"""

from __future__ import annotations

import sys


def asyncio_without_tls() -> None:
    """Imports asyncio without ssl unless one of them is imported already (then nothing
    changes: asyncio keeps the ssl it has)."""
    if "asyncio" in sys.modules or "ssl" in sys.modules:
        return
    sys.modules["ssl"] = None  # type: ignore[assignment]  # `import ssl` raises ImportError
    try:
        import asyncio  # noqa: F401
    finally:
        del sys.modules["ssl"]


__all__ = ["asyncio_without_tls"]
