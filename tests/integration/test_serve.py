"""`tuilaunch serve` in a real browser (Debian's chromium, driven by Selenium): the page of
a served session shows its tree, its keys reach the TUI in order, a page and a terminal
client see each other's changes, `--read-only` refuses, and closing the page or stopping
serve stops nothing.

Each page is one more client of a real session (a detached launch of plain processes),
run by serve as `tuilaunch attach` under Textual's web driver.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from selenium.webdriver.common.keys import Keys

from ..conftest import wait_for
from .browser import Serving, free_port, page, tab_processes
from .session_steps import start_here
from .test_sessions import (  # noqa: F401
    Terminal,
    runtime,
    start_detached,
    status,
    tl,
    wait_state,
)

# the first test may install chromium (apt-get, a few minutes on a slow mirror)
pytestmark = pytest.mark.timeout(900)


class TerminalClient(Terminal):
    """`tuilaunch attach` on a pseudo-terminal, typed into."""

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    def read_since(self, start: int, marker: bytes, limit: float = 60.0) -> None:
        end = time.monotonic() + limit
        while marker not in self.screen[start:]:
            assert time.monotonic() < end, f"{marker!r} never came: {self.screen[-500:]!r}"
            self.pump(0.1)


def states(name: str) -> dict[str, str]:
    return {p["id"]: p["state"] for p in status(name)["processes"]}


def selected(text: str, process: str) -> bool:
    """The detail line (the screen's fourth row) names the selected process."""
    rows = text.splitlines()
    return len(rows) > 3 and rows[3].strip().startswith(f"{process} ")


def tree_shown(text: str) -> bool:
    return all(f"{p}" in text for p in ("test_launch.py", "ticker-1", "echo-3"))


@pytest.fixture
def served(runtime, write):  # noqa: F811  (runtime: a fixture)
    """A session and `tuilaunch serve NAME` on it; everything ends with the test."""
    started: list[Serving] = []

    def serve(*options: str) -> tuple[str, Serving]:
        name = start_detached(write)
        serving = Serving(name, "--port", str(free_port()), *options)
        started.append(serving)
        return name, serving

    yield serve
    for serving in started:
        serving.close()
    wait_for(lambda: not tab_processes(runtime), what="no tab's TUI left")


def test_the_page_shows_the_tree_and_s_stops_the_selected_node(served, runtime):  # noqa: F811
    name, serving = served()
    assert serving.url.startswith("http://127.0.0.1:")
    with page() as browser:
        browser.open(serving.url)
        text = browser.wait_screen(tree_shown, "the session's tree")
        assert f"[{name}] test_launch.py" in text  # the status line, as in a terminal
        assert "▼ test_launch.py" in text  # box drawing and the tree's guides render
        browser.type(Keys.ARROW_DOWN, Keys.ARROW_DOWN)
        browser.wait_screen(lambda t: selected(t, "ticker-1"), "ticker-1 selected")
        browser.type("s")
        wait_for(lambda: states(name)["ticker-1"] == "exited", what="ticker-1 stopped")
        browser.wait_screen(lambda t: "[ticker-1] exited" in t, "ticker-1 exited in the tree")
        assert states(name)["echo-3"] == "running"  # only the selection
        assert len(tab_processes(runtime)) == 1
    # the tab is closed: its TUI leaves, the launch runs on
    wait_for(lambda: not tab_processes(runtime), what="the closed tab's TUI gone")
    assert states(name)["echo-3"] == "running"
    assert serving.proc.poll() is None  # serve serves on


def test_slash_set_typed_in_one_burst_searches_and_stops_nothing(served):
    name, serving = served()
    with page() as browser:
        browser.open(serving.url)
        browser.wait_screen(tree_shown, "the session's tree")
        browser.type(Keys.ARROW_DOWN, Keys.ARROW_DOWN)
        browser.wait_screen(lambda t: selected(t, "ticker-1"), "ticker-1 selected")
        browser.type("/set")  # one burst: its s and t are the search's, not stop and start
        text = browser.wait_screen(lambda t: any(
            row.strip(" ▎▊") == "set" for row in t.splitlines()), "set in the search field")
        assert "Stop" not in text.splitlines()[3]
    running = states(name)
    assert running["ticker-1"] == "running" and running["echo-3"] == "running"


def test_read_only_refuses_s_with_one_line(served):
    name, serving = served("--read-only")
    with page() as browser:
        browser.open(serving.url)
        text = browser.wait_screen(tree_shown, "the session's tree")
        assert f"[{name} read-only]" in text
        browser.type(Keys.ARROW_DOWN, Keys.ARROW_DOWN)
        browser.wait_screen(lambda t: selected(t, "ticker-1"), "ticker-1 selected")
        browser.type("s")
        browser.wait_screen(lambda t: "read-only view: stopping a process is refused" in t,
                            "the refusal")
        assert states(name)["ticker-1"] == "running"


def test_q_in_the_page_leaves_and_the_launch_runs_on(served, runtime):  # noqa: F811
    name, serving = served()
    with page() as browser:
        browser.open(serving.url)
        browser.wait_screen(tree_shown, "the session's tree")
        browser.type("q")
        wait_for(lambda: "-closed" in browser.body_classes(), what="the page says it left")
        wait_for(lambda: not tab_processes(runtime), what="the tab's TUI gone")
        assert set(states(name).values()) >= {"running"}
        assert states(name)["echo-3"] == "running"
    assert serving.stop() == 0
    assert states(name)["echo-3"] == "running"  # stopping serve stopped nothing


def test_a_page_and_a_terminal_client_see_each_others_changes(served):
    name, serving = served()
    terminal = TerminalClient("attach", name)
    try:
        terminal.read_until(b"echo-3")
        terminal.write(b"\x1b[B\x1b[B")  # down, down: ticker-1 selected in the terminal
        terminal.read_until(b"ticker-1 (/ticker): running")  # its detail line
        with page() as browser:
            browser.open(serving.url)
            browser.wait_screen(tree_shown, "the session's tree")
            # the page stops ticker-1: the terminal shows it
            before = len(terminal.screen)
            browser.type(Keys.ARROW_DOWN, Keys.ARROW_DOWN)
            browser.wait_screen(lambda t: selected(t, "ticker-1"), "ticker-1 selected")
            browser.type("s")
            wait_for(lambda: states(name)["ticker-1"] == "exited", what="ticker-1 stopped")
            terminal.read_since(before, b"ticker-1 (/ticker): exited")
            # the terminal starts it again: the page shows it running
            terminal.write(b"t")
            wait_for(lambda: states(name)["ticker-1"] == "running", what="ticker-1 again")
            browser.wait_screen(lambda t: "[ticker-1] running" in t, "ticker-1 running again")
    finally:
        terminal.close()


def test_a_launch_file_is_started_then_served_and_runs_on_after_serve(runtime, write):  # noqa: F811
    path: Path = write("""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([DeclareLaunchArgument('word', default_value='a'),
        ExecuteProcess(name='sleeper', cmd=['sleep', '600']),
        ExecuteProcess(name='say', cmd=['sh', '-c', 'echo said $0; exec sleep 600',
                                        LaunchConfiguration('word')])])
""", "served_launch.py")
    serving = Serving(str(path), "word:=zebra", "--name", "web", "--port", str(free_port()))
    try:
        assert serving.url.startswith("http://127.0.0.1:")
        assert states("web") == {"sleeper-1": "running", "say-2": "running"}
        assert status("web")["arguments"] == {"word": "zebra"}
        with page() as browser:
            browser.open(serving.url)
            browser.wait_screen(lambda t: "sleeper-1" in t and "say-2" in t, "the tree")
        assert serving.stop() == 0
        assert "session web runs on" in serving.errors()
        assert states("web")["sleeper-1"] == "running"
    finally:
        serving.close()


class PrefixProxy:
    """A reverse proxy, as nginx's `location /tl/ { proxy_pass http://127.0.0.1:PORT/; }`
    with `proxy_set_header Host $host` and the websocket upgrade: requests under /tl/ go
    to serve without the prefix. On a loop of its own thread (the browser test is sync)."""

    def __init__(self, upstream: int) -> None:
        import asyncio
        import threading

        self.upstream = upstream
        self.port = free_port()
        self.loop = asyncio.new_event_loop()
        self.ready = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        assert self.ready.wait(30)

    def _run(self) -> None:
        import asyncio

        from aiohttp import web

        asyncio.set_event_loop(self.loop)
        app = web.Application()
        app.router.add_route("GET", "/tl/{rest:.*}", self._forward)
        self.runner = web.AppRunner(app, access_log=None)
        self.loop.run_until_complete(self.runner.setup())
        self.loop.run_until_complete(web.TCPSite(self.runner, "127.0.0.1", self.port).start())
        self.ready.set()
        self.loop.run_forever()

    async def _forward(self, request):
        import asyncio

        import aiohttp
        from aiohttp import web

        target = f"http://127.0.0.1:{self.upstream}/{request.match_info['rest']}"
        if request.query_string:
            target += "?" + request.query_string
        headers = {"Host": request.host}
        for name in ("Cookie", "Origin"):
            if name in request.headers:
                headers[name] = request.headers[name]
        async with aiohttp.ClientSession(auto_decompress=False) as client:
            if request.headers.get("Upgrade", "").lower() == "websocket":
                async with client.ws_connect(target, headers=headers) as upstream:
                    page = web.WebSocketResponse()
                    await page.prepare(request)

                    async def down():
                        async for message in upstream:
                            if message.type == aiohttp.WSMsgType.BINARY:
                                await page.send_bytes(message.data)
                            elif message.type == aiohttp.WSMsgType.TEXT:
                                await page.send_str(message.data)
                        await page.close()

                    async def up():
                        async for message in page:
                            if message.type == aiohttp.WSMsgType.TEXT:
                                await upstream.send_str(message.data)
                        await upstream.close()

                    await asyncio.gather(down(), up())
                    return page
            async with client.get(target, headers=headers, allow_redirects=False) as answer:
                response = web.Response(status=answer.status, body=await answer.read())
                for name in ("Content-Type", "Location", "Content-Encoding"):
                    if name in answer.headers:
                        response.headers[name] = answer.headers[name]
                for cookie in answer.headers.getall("Set-Cookie", []):
                    response.headers.add("Set-Cookie", cookie)
                return response

    def close(self) -> None:
        import asyncio

        asyncio.run_coroutine_threadsafe(self.runner.cleanup(), self.loop).result(30)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(30)


def test_behind_a_reverse_proxy_with_a_path_and_a_token(runtime, write, tmp_path):  # noqa: F811
    name = start_detached(write)
    token = tmp_path / "token"
    token.write_text("proxy-token-0123456789abcdef\n")
    upstream = free_port()
    proxy = PrefixProxy(upstream)
    public = f"http://127.0.0.1:{proxy.port}/tl/"
    serving = Serving(name, "--port", str(upstream), "--public-url", public,
                      "--token-file", str(token))
    try:
        assert serving.url == public + "?token=proxy-token-0123456789abcdef"
        with page() as browser:
            browser.open(serving.url)  # redirected within /tl/, the cookie kept for /tl
            browser.wait_screen(tree_shown, "the session's tree through the proxy")
            assert browser.driver.current_url == public
            browser.type(Keys.ARROW_DOWN, Keys.ARROW_DOWN)
            browser.wait_screen(lambda t: selected(t, "ticker-1"), "ticker-1 selected")
            browser.type("s")
            wait_for(lambda: states(name)["ticker-1"] == "exited", what="ticker-1 stopped")
    finally:
        serving.close()
        proxy.close()
    wait_for(lambda: not tab_processes(runtime), what="no tab's TUI left")


def test_a_resized_window_lays_the_app_out_again(served):
    def tree_width(text: str) -> int:
        """Where the tree's pane ends, on its first row (a share of the width)."""
        row = next((r for r in text.splitlines() if r.startswith("▼ test_launch.py")), "")
        return row.find("▎")

    name, serving = served()
    with page() as browser:
        browser.open(serving.url)
        # 1100 px: about 122 columns, the tree a third of them (its first frames may come
        # at the page's size before its font loaded: narrower)
        wide = tree_width(browser.wait_screen(
            lambda t: tree_shown(t) and tree_width(t) >= 38, "the session's tree, wide"))
        # 800 px: about 88 columns, the tree beside the pane still (below 70 it goes above)
        browser.driver.set_window_size(800, 600)
        narrow = browser.wait_screen(
            lambda t: tree_shown(t) and 0 < tree_width(t) < wide * 0.8,
            "the app laid out for the narrower window")
        assert f"[{name}] test_launch.py" in narrow


LONG = "a_very_long_node_name_of_30_ch"


def test_a_phone_has_the_tree_above_the_pane_and_the_nodes_keys(runtime, write):  # noqa: F811
    """390x844, a phone held upright (about 43 columns): a 30-character name whole on its
    row, the tree above the pane; the footer's two rows offer Stop, Restart, Start, Type,
    Search and the palette; a tap on the row selects it, a tap on Stop stops it."""
    path = write(f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='ticker', cmd=['sleep', '600']),
                              ExecuteProcess(name='{LONG}', cmd=['sleep', '600'])])
""", "phone_launch.py")
    name = start_here(path)
    wait_state(name, f"{LONG}-2", "running")
    serving = Serving(name, "--port", str(free_port()))
    try:
        with page() as browser:
            browser.driver.set_window_size(390, 844)
            browser.open(serving.url)
            text = browser.wait_screen(lambda t: f"● {LONG} [" in t, "the long name whole")
            rows = text.splitlines()
            at = next(i for i, row in enumerate(rows) if LONG in row)
            # the tree is the whole width (no pane's edge beside it); the pane's own
            # status line comes below it, at the left edge
            assert "▎" not in "".join(rows[4:at + 1])
            assert any(row.startswith("all nodes") for row in rows[at + 1:])
            footer = browser.wait_screen(lambda t: all(
                key in "\n".join(t.splitlines()[-2:]) for key in (
                    "s Stop", "r Restart", "t Start", "i Type", "/ Search", "^p palette")),
                "the node's keys in the footer's two rows")
            browser.tap(LONG, at)
            browser.wait_screen(lambda t: t.splitlines()[3].strip().startswith(f"{LONG}-2"),
                                "the long row selected by a tap")
            browser.tap("Stop", len(footer.splitlines()) - 2)
            wait_for(lambda: states(name)[f"{LONG}-2"] == "exited",
                     what="the long-named node stopped by a tap on Stop")
            assert states(name)["ticker-1"] == "running"  # only the selection
    finally:
        serving.close()
    wait_for(lambda: not tab_processes(runtime), what="no tab's TUI left")
