"""Who may open `tuilaunch serve`'s pages and drive its tabs, tested with plain HTTP and
websocket clients (aiohttp's) against a real `tuilaunch serve` on a real session: no token,
a wrong token, the token in the URL then its cookie, a cross-site Origin, a Host that is
not this machine's (DNS rebinding), a port in use, and the token kept out of every log.
"""

from __future__ import annotations

import asyncio
import json
import os
import socket
import subprocess
import sys
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

import aiohttp
import pytest

from ..conftest import run_cli, wait_for
from .browser import Serving, free_port, tab_processes
from .proc_tree import cmdline, descendants
from .test_sessions import runtime, start_detached, status  # noqa: F401

TOKEN = "correct-horse-battery-staple-42"


@pytest.fixture
def session(runtime, write):  # noqa: F811  (runtime: a fixture)
    name = start_detached(write)
    yield name
    wait_for(lambda: not tab_processes(runtime), what="no tab's TUI left")


@pytest.fixture
def token_file(tmp_path: Path) -> Path:
    path = tmp_path / "token"
    path.write_text(TOKEN + "\n")
    return path


def fetch(url: str, **options) -> tuple[int, dict[str, str], str, list]:
    """One GET, redirects not followed: status, headers, text and the cookies set."""
    async def get():
        async with aiohttp.ClientSession() as client, \
                client.get(url, allow_redirects=False, **options) as response:
            return (response.status, dict(response.headers), await response.text(),
                    response.headers.getall("Set-Cookie", []))
    return asyncio.run(get())


def websocket(url: str, **options) -> tuple[int, bytes]:
    """A websocket to a tab: the handshake's status (101 once open) and the first bytes the
    tab's TUI sends (its first frame), or (status, b"") when refused."""
    async def connect():
        async with aiohttp.ClientSession() as client:
            try:
                async with client.ws_connect(url, **options) as ws:
                    received = b""
                    while b"test_launch.py" not in received:
                        message = await asyncio.wait_for(ws.receive(), 90)
                        if message.type != aiohttp.WSMsgType.BINARY:
                            break
                        received += message.data
                    return 101, received
            except aiohttp.WSServerHandshakeError as exc:
                return exc.status, b""
    return asyncio.run(connect())


def ws_url(url: str) -> str:
    parts = urlsplit(url)
    return f"ws://{parts.netloc}/ws?width=80&height=24"


def test_with_a_token_nothing_is_served_without_it(session, token_file):
    serving = Serving(session, "--port", str(free_port()), "--token-file", str(token_file))
    try:
        url = serving.url
        assert parse_qs(urlsplit(url).query) == {"token": [TOKEN]}  # printed once, in the URL
        base = url.split("?")[0]
        code, _, text, _ = fetch(base)
        assert code == 401 and "needs the token" in text
        assert fetch(base + "static/js/textual.js")[0] == 401  # every request, files too
        assert fetch(base + "?token=wrong")[0] == 403
        assert fetch(base, cookies={f"tuilaunch_token_{urlsplit(url).port}": "wrong"})[0] \
            == 403
        # the right token: a redirect to the same page without it, and the cookie
        code, headers, _, cookies = fetch(url)
        assert code == 303 and headers["Location"] == "./"
        (cookie,) = cookies
        name, value = cookie.split(";")[0].split("=", 1)
        assert value == TOKEN
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie and "Path=/" in cookie
        code, headers, page, _ = fetch(base, cookies={name: value})
        assert code == 200 and "textual.js" in page
        assert headers["X-Frame-Options"] == "DENY"  # never framed by another site
        assert headers["Referrer-Policy"] == "no-referrer"
        assert fetch(base + "static/js/textual.js", cookies={name: value})[0] == 200
        # the websocket: refused without the cookie, and from another site even with it
        assert websocket(ws_url(url))[0] == 401
        assert websocket(ws_url(url), headers={"Cookie": f"{name}=wrong"})[0] == 403
        assert websocket(ws_url(url), headers={
            "Cookie": f"{name}={value}", "Origin": "http://evil.example"})[0] == 403
        assert not tab_processes_of(serving)  # nothing refused started a TUI
        # the page's own origin, with the cookie: the tab's TUI draws the session
        code, frame = websocket(ws_url(url), headers={
            "Cookie": f"{name}={value}", "Origin": f"http://{urlsplit(url).netloc}"})
        assert code == 101 and b"test_launch.py" in frame
    finally:
        assert serving.stop() == 0
        serving.close()
    # said once, in the URL: no log line, no error output carries it
    assert TOKEN not in serving.rest
    assert TOKEN not in serving.errors()
    assert status(session)["processes"]  # the session runs on


def tab_processes_of(serving: Serving) -> list[int]:
    return [p for p in descendants(serving.proc.pid) if b"attach" in cmdline(p)]


def test_loopback_without_a_token_refuses_other_sites_and_other_names(session):
    serving = Serving(session, "--port", str(free_port()))
    try:
        url = serving.url
        assert "token" not in url
        assert fetch(url)[0] == 200
        port = urlsplit(url).port
        # a name of another site re-pointed at 127.0.0.1 (DNS rebinding): refused
        code, _, text, _ = fetch(url, headers={"Host": f"evil.example:{port}"})
        assert code == 403 and "127.0.0.1 only" in text
        assert fetch(url, headers={"Host": f"localhost:{port}"})[0] == 200
        assert websocket(ws_url(url), headers={"Origin": "http://evil.example"})[0] == 403
        code, frame = websocket(ws_url(url), headers={"Origin": f"http://127.0.0.1:{port}"})
        assert code == 101 and b"test_launch.py" in frame
    finally:
        serving.stop()
        serving.close()


def test_any_other_address_gets_a_random_token(session):
    serving = Serving(session, "--host", "0.0.0.0", "--port", str(free_port()))
    try:
        token = parse_qs(urlsplit(serving.url).query)["token"][0]
        assert len(token) >= 40
        local = f"http://127.0.0.1:{urlsplit(serving.url).port}/"
        assert fetch(local)[0] == 401
        assert fetch(local + "?token=" + token)[0] == 303
    finally:
        serving.stop()
        serving.close()
    again = Serving(session, "--host", "0.0.0.0", "--port", str(free_port()))
    try:  # made at each start
        assert parse_qs(urlsplit(again.url).query)["token"][0] != token
    finally:
        again.stop()
        again.close()


def test_a_port_in_use_and_bad_options_are_one_line(session, tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = run_cli("serve", session, "--port", str(port))
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.splitlines()[0] == \
        f"tuilaunch serve: error: port {port} on 127.0.0.1 is in use"
    empty = tmp_path / "empty"
    empty.write_text("\n")
    done = run_cli("serve", session, "--token-file", str(empty))
    assert done.returncode == 2 and "--token-file" in done.stderr and "missing" in \
        done.stderr and "Traceback" not in done.stderr
    done = run_cli("serve", "nosuchsession")
    assert done.returncode == 2
    assert "no running session named nosuchsession" in done.stderr


def test_serve_alone_lists_the_sessions_and_opens_the_one_picked(session):
    serving = Serving("--port", str(free_port()))
    try:
        code, _, page, _ = fetch(serving.url)
        assert code == 200
        assert f"href='s/{session}/'" in page and "test_launch.py" in page
        code, _, tui, _ = fetch(serving.url + f"s/{session}/")
        assert code == 200 and "../../static/js/textual.js" in tui
        assert fetch(serving.url + "s/nosuch/")[0] == 404
        port = urlsplit(serving.url).port
        code, frame = websocket(f"ws://127.0.0.1:{port}/s/{session}/ws",
                                headers={"Origin": f"http://127.0.0.1:{port}"})
        assert code == 101 and b"test_launch.py" in frame
    finally:
        serving.stop()
        serving.close()


def test_attach_refuses_a_pipe_but_not_the_web_driver(session):
    """attach still needs a terminal, unless textual-serve runs it with the web driver:
    then its first bytes are the driver's greeting, not an error."""
    done = run_cli("attach", session)
    assert done.returncode == 2 and "attach needs a terminal" in done.stderr
    proc = subprocess.Popen(
        [sys.executable, "-m", "tuilaunch", "attach", session], stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        env={**os.environ,
             "TEXTUAL_DRIVER": "textual.drivers.web_driver:WebDriver"})
    try:
        assert proc.stdout is not None and proc.stdin is not None
        assert proc.stdout.readline() == b"__GANGLION__\n"
        # the page's quit (textual-serve's meta packet): the TUI leaves
        quit_meta = json.dumps({"type": "quit"}).encode()
        proc.stdin.write(b"M" + len(quit_meta).to_bytes(4, "big") + quit_meta)
        proc.stdin.flush()
        assert proc.wait(timeout=60) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert status(session)["processes"]  # the session runs on
