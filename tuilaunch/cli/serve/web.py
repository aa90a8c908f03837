"""The web side of `tuilaunch serve`: aiohttp pages and one TUI process per browser tab.

Imported only by `tuilaunch serve` (aiohttp and textual-serve are not light): the launcher,
the TUI and the other commands never load it (tests/integration/test_light.py).

Each tab's websocket runs `tuilaunch attach NAME ...` (several: the fleet view) under
Textual's web driver through textual-serve's `AppService` (its process, the packets of its
pipes, resizes); the page is our own (no font or script from another site: a robot's
network may have no internet, and its page must not call out), using textual-serve's
xterm.js client and font. Every request passes serve_guard.py's rules first.
"""

from __future__ import annotations

import asyncio
import html
import json
import logging
import signal
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlencode

import textual_serve
from aiohttp import WSMsgType, web
from textual_serve.download_manager import DownloadManager

from ...engine.run.session import session_dir
from .guard import Guard
from .tabs import Early, TabService, Warm, tab_words

STATIC = Path(textual_serve.__file__).parent / "static"
FONT = "fonts/RobotoMono-VariableFont_wght.ttf"
STOP_GRACE = 5.0
"""Seconds a tab's TUI has to leave once asked (serve stopping), before it is killed."""

log = logging.getLogger("tuilaunch.serve")


class ServeApp:
    """The pages and websockets of one `tuilaunch serve`: the TUI of `sessions` at `/` (one
    session's, or the fleet view of several), or (none given) a page listing this machine's
    sessions at `/`, each one's TUI at `/s/NAME/` and all of them together at `/fleet/`."""

    def __init__(self, guard: Guard, sessions: list[str], read_only: bool,
                 list_sessions: Callable[[], list[dict[str, Any]]]) -> None:
        self.guard = guard
        self.sessions = sessions
        self.read_only = read_only
        self.list_sessions = list_sessions
        self.tabs: set[TabService] = set()
        self.sockets: set[web.WebSocketResponse] = set()
        self.downloads = DownloadManager()
        self.warm = Warm()
        self.early = Early(self._make_tab)

    def make(self) -> web.Application:
        app = web.Application(middlewares=[self._guard])
        app.add_routes([
            web.get("/", self.index),
            web.get("/ws", self.websocket),
            web.get("/ws/{ticket}", self.websocket),
            web.get("/s/{name}/", self.session_page),
            web.get("/s/{name}/ws", self.websocket),
            web.get("/s/{name}/ws/{ticket}", self.websocket),
            web.get("/fleet/", self.fleet_page),
            web.get("/fleet/ws", self.fleet_websocket),
            web.get("/fleet/ws/{ticket}", self.fleet_websocket),
            web.get("/download/{key}", self.download),
            web.static("/static", STATIC),
        ])
        app.on_shutdown.append(self._close_tabs)
        return app

    # --- the rules, on every request -------------------------------------------------------

    @web.middleware
    async def _guard(self, request: web.Request,
                     handler: Callable[[web.Request], Awaitable[web.StreamResponse]],
                     ) -> web.StreamResponse:
        query = request.rel_url.query
        kept = [(k, v) for k, v in query.items() if k != "token"]
        # relative to where the browser is: right behind a proxy's prefix too
        location = "./" + request.rel_url.path.rsplit("/", 1)[-1] + \
            (f"?{urlencode(kept)}" if kept else "")
        verdict = self.guard.check(
            scheme=request.scheme, host_header=request.host,
            origin=request.headers.get("Origin"),
            websocket=request.headers.get("Upgrade", "").lower() == "websocket",
            query_token=query.get("token"),
            cookie_token=request.cookies.get(self.guard.cookie_name),
            path_without_token=location)
        if verdict.status == 303:
            response: web.StreamResponse = web.HTTPSeeOther(location)
            response.set_cookie(self.guard.cookie_name, self.guard.token or "", httponly=True,
                                samesite="Strict", path=self.guard.cookie_path,
                                secure=self.guard.cookie_secure)
        elif verdict.status:
            response = web.Response(status=verdict.status, text=verdict.text + "\n")
        else:
            response = await handler(request)
        # a page that drives a robot: never inside another site's frame, never cached, and
        # its address (a token in it) never sent on as a referrer
        response.headers["X-Frame-Options"] = "DENY"
        response.headers["Content-Security-Policy"] = "frame-ancestors 'none'"
        response.headers["Referrer-Policy"] = "no-referrer"
        # textual-serve's script and font (700 KB) are kept an hour by the browser: a
        # page opened again loads at once
        response.headers.setdefault("Cache-Control", "private, max-age=3600" if
                                    "/static/" in request.path else "no-store")
        return response

    # --- pages -----------------------------------------------------------------------------

    async def index(self, request: web.Request) -> web.Response:
        if self.sessions:
            gone = [s for s in self.sessions if ":" not in s and not session_dir.is_alive(s)]
            if len(self.sessions) == 1 and gone:  # a fleet view says an ended one itself
                raise web.HTTPNotFound(text=f"tuilaunch serve: session {gone[0]} is not "
                                       "running (any more)\n")
            return await self._tui_page(request, " ".join(self.sessions), "static/",
                                        self.sessions)
        sessions = await asyncio.get_running_loop().run_in_executor(None, self.list_sessions)
        return web.Response(text=sessions_page(sessions, self.read_only),
                            content_type="text/html")

    async def session_page(self, request: web.Request) -> web.Response:
        name = self._listed(request)
        return await self._tui_page(request, name, "../../static/", [name])

    async def fleet_page(self, request: web.Request) -> web.Response:
        return await self._tui_page(request, "every session", "../static/",
                                    await self._fleet())

    async def _fleet(self) -> list[str]:
        """`/fleet/`: every session of this machine that answers, in one fleet view."""
        if self.sessions:
            raise web.HTTPNotFound(text="tuilaunch serve: no fleet page here\n")
        listed = await asyncio.get_running_loop().run_in_executor(None, self.list_sessions)
        names = [str(s["name"]) for s in listed if s.get("answering")]
        if not names:
            raise web.HTTPNotFound(text="tuilaunch serve: no running session here\n")
        return names

    def _listed(self, request: web.Request) -> str:
        """`/s/NAME/`: a session of this machine, on the page that lists them."""
        name = request.match_info["name"]
        if self.sessions or not session_dir.is_alive(name):
            raise web.HTTPNotFound(text=f"tuilaunch serve: no session {name} here\n")
        return name

    async def _tui_page(self, request: web.Request, name: str, static: str,
                        sessions: list[str]) -> web.Response:
        """The page; its TUI starts now (serve_tabs.py), its websocket names it."""
        font = request.rel_url.query.get("fontsize", "16")
        size = int(font) if font.isdigit() and 6 <= int(font) <= 64 else 16
        ticket = await self.early.start(tab_words(sessions, self.read_only))
        return web.Response(text=tui_page(name, static, size, self.read_only, ticket),
                            content_type="text/html")

    def _make_tab(self, words: list[str], **writers: Any) -> TabService:
        tab = TabService(words, self.warm, download_manager=self.downloads, **writers)
        self.tabs.add(tab)
        return tab

    async def download(self, request: web.Request) -> web.StreamResponse:
        """A file a tab's TUI hands the browser (`w` on the output pane: Textual's
        deliver_text), by its single-use key; the page opens this address."""
        key = request.match_info["key"]
        try:
            meta = await self.downloads.get_download_metadata(key)
        except KeyError:
            raise web.HTTPNotFound(text="tuilaunch serve: no such download (each is "
                                   "fetched once)\n") from None
        response = web.StreamResponse()
        response.content_type = meta.mime_type
        if meta.encoding:
            response.charset = meta.encoding
        disposition = "inline" if meta.open_method == "browser" else "attachment"
        file_name = meta.file_name.replace('"', "")
        response.headers["Content-Disposition"] = f'{disposition}; filename="{file_name}"'
        await response.prepare(request)
        async for chunk in self.downloads.download(key):
            await response.write(chunk)
        await response.write_eof()
        return response

    # --- a tab ------------------------------------------------------------------------------

    async def fleet_websocket(self, request: web.Request) -> web.WebSocketResponse:
        return await self.websocket(request, await self._fleet())

    async def websocket(self, request: web.Request,
                        sessions: list[str] | None = None) -> web.WebSocketResponse:
        if sessions is None:
            sessions = [self._listed(request)] if "name" in request.match_info else \
                self.sessions
        websocket = web.WebSocketResponse(heartbeat=15)
        await websocket.prepare(request)
        self.sockets.add(websocket)
        width = _number(request.rel_url.query.get("width"), 80)
        height = _number(request.rel_url.query.get("height"), 24)

        async def close() -> None:
            await websocket.close()

        words = tab_words(sessions, self.read_only)
        writers: dict[str, Any] = {"write_bytes": websocket.send_bytes,
                                   "write_str": websocket.send_str, "close": close}
        tab = await self.early.claim(request.match_info.get("ticket", ""), words,
                                     websocket.send_bytes, websocket.send_str, close)
        try:
            if tab is None:  # no TUI started with the page (or another's ticket)
                tab = self._make_tab(words, **writers)
                await tab.start(width, height)
            else:
                await tab.set_terminal_size(width, height)
            await self._relay(websocket, tab)
        finally:
            # the tab closed, or serve stops: the TUI leaves (the launch runs on)
            if tab is not None:
                await self._stop_tab(tab)
                self.tabs.discard(tab)
            self.sockets.discard(websocket)
        return websocket

    async def _relay(self, websocket: web.WebSocketResponse, tab: TabService) -> None:
        """The page's keys, sizes and focus to the tab's TUI (textual-serve's envelope)."""
        async for message in websocket:
            if message.type != WSMsgType.TEXT:
                continue
            try:
                kind, data = json.loads(message.data)
            except (ValueError, TypeError):
                continue  # not the page's: ignored, as textual-serve's own server would
            if kind == "stdin" and isinstance(data, str):
                await tab.send_bytes(data.encode("utf-8"))
            elif kind == "resize" and isinstance(data, dict):
                await tab.set_terminal_size(_number(data.get("width"), 80),
                                            _number(data.get("height"), 24))
            elif kind == "ping":
                await websocket.send_json(["pong", data])
            elif kind == "blur":
                await tab.blur()
            elif kind == "focus":
                await tab.focus()

    async def _stop_tab(self, tab: TabService) -> None:
        try:
            await asyncio.wait_for(tab.stop(), STOP_GRACE)
        except (TimeoutError, ConnectionError, RuntimeError):
            pass
        tab.kill()  # asked to quit and still there: it goes, the session stays

    async def _close_tabs(self, app: web.Application) -> None:
        """serve stops: each tab's page is told (its websocket closes), each TUI leaves."""
        for websocket in list(self.sockets):
            await websocket.close(code=1001, message=b"tuilaunch serve stopped")


def _number(value: Any, default: int) -> int:
    try:
        return max(1, min(int(value), 1000))
    except (TypeError, ValueError):
        return default


PAGE_STYLE = """
@font-face { font-family: 'Roboto Mono';
             src: url('{static}{font}'); }
body { background: #0c181f; color: #e0e0e0; margin: 0; font-family: 'Roboto Mono', monospace; }
.textual-terminal { opacity: 0; }
body.-first-byte .textual-terminal { opacity: 1; }
.closed { display: none; position: absolute; inset: 0; align-items: center;
          justify-content: center; flex-direction: column; background: #0c181f; }
body.-closed .closed { display: flex; }
.closed a, table a { color: #8ab4f8; }
table { border-collapse: collapse; margin: 2em; }
td, th { padding: 0.3em 1em; text-align: left; border-bottom: 1px solid #234; }
h1 { font-size: 1.2em; margin: 2em 2em 0; }
"""


def _head(title: str, static: str) -> str:
    style = PAGE_STYLE.replace("{static}", static).replace("{font}", FONT)
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'>"
            f"<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>{html.escape(title)}</title><style>{style}</style>")


def tui_page(name: str, static: str, font_size: int, read_only: bool,
             ticket: str = "") -> str:
    """A session's TUI in the page: textual-serve's client reads the websocket's address
    from the terminal element. The static files and the websocket (`ws` beside the page,
    `ws/TICKET` for the TUI started with the page) are addressed relative to the page, so
    a reverse proxy's prefix carries over. The font is asked for with the script, not
    once the script has run (it is the page's last file otherwise)."""
    title = f"{name}{' (read-only)' if read_only else ''} - tuilaunch"
    socket = f"ws/{ticket}" if ticket else "ws"
    script = (f"<script>(function(){{var u=new URL('{socket}', location.href);"
              "u.protocol=location.protocol==='https:'?'wss:':'ws:';u.search='';u.hash='';"
              "document.getElementById('terminal').dataset.sessionWebsocketUrl=u.href;})();"
              "</script>")
    return (_head(title, static)
            + f"<link rel='preload' href='{static}{FONT}' as='font' type='font/ttf' "
            + "crossorigin>"
            + f"<link rel='stylesheet' href='{static}css/xterm.css'>"
            + f"<script src='{static}js/textual.js'></script></head><body>"
            + f"<div id='terminal' class='textual-terminal' data-font-size='{font_size}'>"
            + "</div>" + script
            + f"<div class='closed'><p>This tab left session {html.escape(name)} (the "
            + "launch runs on, unless it was stopped).</p>"
            + "<p><a href=''>Open it again</a></p></div></body></html>")


def sessions_page(sessions: list[dict[str, Any]], read_only: bool) -> str:
    """`tuilaunch serve` alone: the sessions as `ls` lists them, each a link to its TUI."""
    rows = []
    for s in sessions:
        counts = s.get("counts") or {}
        total = sum(n for state, n in counts.items() if state != "skipped")
        running = f"{counts.get('running', 0)}/{total}" if s.get("answering") else "?"
        arguments = " ".join(f"{k}:={v}" for k, v in (s.get("arguments") or {}).items())
        name = html.escape(str(s["name"]))
        link = f"<a href='s/{name}/'>{name}</a>" if s.get("answering") else name
        rows.append(f"<tr><td>{link}</td><td>{running}</td>"
                    f"<td>{html.escape(str(s.get('file', '')))}</td>"
                    f"<td>{html.escape(arguments)}</td></tr>")
    answering = sum(1 for s in sessions if s.get("answering"))
    fleet = "<p style='margin: 0 2em'><a href='fleet/'>All of them in one view</a> (the " \
        "fleet view: a tree per session)</p>" if answering > 1 else ""
    body = ("<table><tr><th>session</th><th>running</th><th>file</th><th>arguments</th></tr>"
            + "".join(rows) + "</table>" + fleet) if rows else \
        "<p style='margin: 2em'>no running sessions (tuilaunch FILE --detach starts one; " \
        "reload this page then)</p>"
    title = f"tuilaunch sessions{' (read-only)' if read_only else ''}"
    return (_head(title, "static/") + "</head><body>"
            + f"<h1>{html.escape(title)}</h1>{body}</body></html>")


async def serve_until_stopped(app: ServeApp, host: str, port: int,
                              ready: Callable[[], Awaitable[None]]) -> None:
    """Listens (OSError when the port is taken, before anything else happens), awaits
    `ready` (a session started, the URL printed), then serves until SIGINT or SIGTERM;
    then every tab's TUI leaves."""
    runner = web.AppRunner(app.make(), access_log=None, handle_signals=False,
                           shutdown_timeout=STOP_GRACE)
    await runner.setup()
    try:
        site = web.TCPSite(runner, host, port)
        await site.start()
        await app.warm.start()  # importing while the URL is said and opened
        await ready()
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for number in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            loop.add_signal_handler(number, stop.set)
        await stop.wait()
    finally:
        app.warm.stop()
        app.early.stop()
        await runner.cleanup()
        for tab in list(app.tabs):  # a TUI that did not leave in time
            tab.kill()


__all__ = ["ServeApp", "serve_until_stopped", "sessions_page", "tab_words", "tui_page"]
