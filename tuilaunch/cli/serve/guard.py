"""Who may open `tuilaunch serve`'s pages and drive its tabs: the token, its cookie, the
Host and Origin rules. Plain decisions on a request's parts (no web framework here), so
serve_web.py applies them to every request and each rule can be read in one place.

- Loopback (the default) without `--token-file`: no token, as ssh -L reaches it; but the
  Host header must name this machine's loopback (or the `--public-url`'s host), so a web
  page whose name is re-pointed at 127.0.0.1 (DNS rebinding) is refused.
- Any other address, or `--token-file`: every request needs the token, given once in the
  URL (`?token=...`, then a redirect without it that sets an HttpOnly, SameSite=Strict
  cookie) or in that cookie; compared in constant time.
- A websocket upgrade (a tab's keys reach the launch through it) whose Origin is not the
  page's own is refused whatever the token: a cross-site page must not drive the robot.
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit

from ...engine.errors import LaunchError

LOOPBACK_NAMES = frozenset({"localhost", "localhost.localdomain", "ip6-localhost"})


def is_loopback(host: str) -> bool:
    host = host.strip("[]")
    if host.lower() in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def host_name(header: str) -> str:
    """The name of a Host header, without its port ("[::1]:8000" -> "::1")."""
    header = header.strip().lower()
    if header.startswith("["):
        return header[1:].split("]", 1)[0]
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


def read_token(path: str) -> str:
    """`--token-file`: its first line; an unreadable or empty file is one line of error."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise LaunchError(f"--token-file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise LaunchError(f"--token-file {path}: not UTF-8 text") from None
    token = (text.splitlines() or [""])[0].strip()
    if len(token) < 16:
        raise LaunchError(f"--token-file {path}: the token on its first line is "
                          f"{'missing' if not token else 'shorter than 16 characters'}",
                          hint="e.g. python3 -c 'import secrets; print(secrets."
                          "token_urlsafe(32))' > FILE")
    return token


@dataclass(frozen=True)
class Verdict:
    """What to do with a request: pass it on (status 0), refuse it (401, 403, with
    `text`), or redirect it (303 to `location`, setting the cookie)."""

    status: int = 0
    text: str = ""
    location: str = ""


PASS = Verdict()


@dataclass(frozen=True)
class Guard:
    token: str | None
    """None: no token asked (loopback without --token-file)."""
    cookie_name: str
    listen_host: str
    public_url: str | None = None

    @classmethod
    def make(cls, host: str, port: int, token_file: str | None,
             public_url: str | None) -> Guard:
        """A random token unless on loopback without --token-file."""
        if token_file is not None:
            token: str | None = read_token(token_file)
        elif is_loopback(host):
            token = None
        else:
            token = secrets.token_urlsafe(32)
        # one per port: two serves on one machine keep cookies of their own
        return cls(token, f"tuilaunch_token_{port}", host, public_url)

    @property
    def cookie_path(self) -> str:
        return (urlsplit(self.public_url).path.rstrip("/") or "/") if self.public_url \
            else "/"

    @property
    def cookie_secure(self) -> bool:
        return bool(self.public_url and self.public_url.startswith("https:"))

    def right(self, given: str | None) -> bool:
        """The token given is ours (constant time: how much of it matched is not told)."""
        if self.token is None or given is None:
            return False
        return hmac.compare_digest(given.encode("utf-8", "replace"),
                                   self.token.encode("utf-8"))

    def allowed_origins(self, scheme: str, host_header: str) -> set[str]:
        origins = {f"{scheme}://{host_header}".lower()}
        if self.public_url:
            parts = urlsplit(self.public_url)
            origins.add(f"{parts.scheme}://{parts.netloc}".lower())
        return origins

    def host_allowed(self, host_header: str) -> bool:
        """Without a token: only this machine's loopback names (or the public URL's) reach
        the pages."""
        if self.token is not None:
            return True
        name = host_name(host_header)
        if is_loopback(name) or name == host_name(self.listen_host):
            return True
        return bool(self.public_url) and name == (urlsplit(self.public_url).hostname or "")

    def check(self, *, scheme: str, host_header: str, origin: str | None, websocket: bool,
              query_token: str | None, cookie_token: str | None, path_without_token: str,
              ) -> Verdict:
        """The verdict on one request. `path_without_token`: its path and query with the
        token taken out, where a right token in the URL redirects to."""
        if not self.host_allowed(host_header):
            return Verdict(403, f"tuilaunch serve: this server answers to 127.0.0.1 only, not "
                           f"{host_name(host_header) or 'a request without Host'}")
        if websocket and origin is not None and \
                origin.lower() not in self.allowed_origins(scheme, host_header):
            return Verdict(403, "tuilaunch serve: a websocket from another site is refused")
        if self.token is None:
            return PASS
        if query_token is not None:
            if not self.right(query_token):
                return Verdict(403, "tuilaunch serve: wrong token")
            if websocket:
                return PASS  # a client of its own (not a page): it keeps the URL it has
            return Verdict(303, location=path_without_token)
        if cookie_token is not None:
            if self.right(cookie_token):
                return PASS
            return Verdict(403, "tuilaunch serve: wrong token (an old cookie? open the URL "
                           "tuilaunch serve printed)")
        return Verdict(401, "tuilaunch serve: this page needs the token: open the URL "
                       "tuilaunch serve printed (it ends in ?token=...)")


__all__ = ["PASS", "Guard", "Verdict", "host_name", "is_loopback", "read_token"]
