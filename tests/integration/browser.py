"""A real browser for the tests of `tuilaunch serve`: Debian's chromium, driven by
Selenium through Debian's chromedriver (no browser is downloaded).

Run as root, the packages are installed when missing
(tests/integration/system_packages.py); otherwise
the tests skip, naming them. The page's terminal is xterm.js drawing on a canvas: what it
shows is read from xterm.js's own screen buffer (the Terminal object textual-serve's client
makes is caught as it is made, by a script run before the page's own), and keys are typed
into xterm.js's hidden textarea, where the page reads them.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from . import proc_tree
from .proc_tree import alive
from .system_packages import apt_install

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1100,700")
DEADLINE = 90.0

CATCH_TERMINAL = """
(function () {
  // textual-serve's client keeps its xterm.js Terminal in a property `terminal` of an
  // object of its own: the first such assignment is caught here, and the Terminal kept
  window.__terminals = [];
  Object.defineProperty(Object.prototype, 'terminal', {
    configurable: true,
    get: function () { return undefined; },
    set: function (value) {
      Object.defineProperty(this, 'terminal', {value: value, writable: true,
                                               configurable: true, enumerable: true});
      if (value && value.buffer && value.onData) window.__terminals.push(value);
    }
  });
})();
"""

READ_SCREEN = """
var t = window.__terminals && window.__terminals[0];
if (!t) return null;
var b = t.buffer.active, rows = [];
for (var i = 0; i < t.rows; i++) {
  var line = b.getLine(b.viewportY + i);
  rows.push(line ? line.translateToString(true) : '');
}
return rows.join('\\n');
"""


def need_chromium() -> None:
    """Installs chromium and chromium-driver when missing and allowed, else skips."""
    for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver")):
        if not os.path.exists(path):
            apt_install(package)
    missing = [p for path, p in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver"))
               if not os.path.exists(path)]
    if missing:
        pytest.skip(f"needs the Debian packages {' and '.join(missing)} (apt-get install "
                    f"{' '.join(missing)}; the tests install them when run as root)")


class Page:
    """One browser window on a served page."""

    def __init__(self) -> None:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        options = webdriver.ChromeOptions()
        options.binary_location = CHROMIUM
        for flag in FLAGS:
            options.add_argument(flag)
        self.profile = tempfile.mkdtemp(prefix="tl-chromium-")
        options.add_argument(f"--user-data-dir={self.profile}")
        self.driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
        self.driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument",
                                    {"source": CATCH_TERMINAL})

    def open(self, url: str) -> None:
        self.driver.get(url)

    def screen(self) -> str:
        """The rows xterm.js shows, as text ('' before the terminal is made)."""
        return self.driver.execute_script(READ_SCREEN) or ""

    def wait_screen(self, check: Callable[[str], object], what: str,
                    timeout: float = DEADLINE) -> str:
        end = time.monotonic() + timeout
        while True:
            text = self.screen()
            if check(text):
                return text
            if time.monotonic() > end:
                raise AssertionError(f"the page never showed {what}; it shows:\n{text}")
            time.sleep(0.1)

    def type(self, *keys: str) -> None:
        """Keys typed into the page, each string in one burst, as a keyboard sends them."""
        from selenium.webdriver.common.action_chains import ActionChains

        self.driver.execute_script(
            "document.querySelector('textarea.xterm-helper-textarea').focus()")
        for key in keys:
            ActionChains(self.driver).send_keys(key).perform()

    def tap(self, text: str, row: int | None = None) -> None:
        """A click (a tap on a tablet) on the middle of `text` where the screen shows it
        (the first row holding it, or `row`), at the cell's place on the page."""
        from selenium.webdriver.common.action_chains import ActionChains

        rows = self.screen().splitlines()
        at = row if row is not None else next(
            (i for i, line in enumerate(rows) if text in line), None)
        assert at is not None and text in rows[at], f"no {text!r} on the screen:\n" + \
            "\n".join(rows)
        column = rows[at].index(text) + len(text) / 2
        cols, lines, width, height = self.driver.execute_script(
            "var t = window.__terminals[0], r = document.querySelector('.xterm-screen')"
            ".getBoundingClientRect(); return [t.cols, t.rows, r.width, r.height];")
        screen = self.driver.find_element("css selector", ".xterm-screen")
        # offsets from the element's centre (Selenium 4)
        ActionChains(self.driver).move_to_element_with_offset(
            screen, int(column * width / cols - width / 2),
            int((at + 0.5) * height / lines - height / 2)).click().perform()

    def catch_downloads(self) -> None:
        """The page's downloads (window.open of serve's /download/KEY) kept in
        window.__opened instead of opening a tab: read with `opened`."""
        self.driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {
            "source": "window.__opened = []; window.open = function (u) "
                      "{ window.__opened.push(String(u)); return null; };"})

    def opened(self) -> list[str]:
        return list(self.driver.execute_script("return window.__opened || []"))

    def body_classes(self) -> str:
        return str(self.driver.execute_script("return document.body.className"))

    def close(self) -> None:
        try:
            self.driver.quit()
        finally:
            shutil.rmtree(self.profile, ignore_errors=True)


@contextmanager
def page() -> Iterator[Page]:
    need_chromium()
    opened = Page()
    try:
        yield opened
    finally:
        opened.close()


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Serving:
    """`tuilaunch serve ...` running: its URL (the first line of its stdout)."""

    def __init__(self, *args: str, env: dict[str, str] | None = None) -> None:
        self.err = Path(tempfile.mkstemp(prefix="tl-serve-", suffix=".err")[1])
        with open(self.err, "wb") as errors:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "tuilaunch", "serve", *args], stdout=subprocess.PIPE,
                stderr=errors, stdin=subprocess.DEVNULL, text=True, start_new_session=True,
                env=env)
        assert self.proc.stdout is not None
        self.url = self.proc.stdout.readline().strip()
        assert self.url.startswith("http"), \
            f"no URL first: {self.url!r}; stderr: {self.errors()}"
        self.rest = ""
        self.written = ""

    def errors(self) -> str:
        """What it wrote on stderr (kept once it is closed)."""
        if self.err.exists():
            self.written = self.err.read_text(errors="replace")
        return self.written

    def stop(self) -> int:
        """Ctrl+C, as a user stops it; what it printed after the URL is kept in `rest`."""
        if self.proc.poll() is None:
            self.proc.send_signal(2)
        try:
            out, _ = self.proc.communicate(timeout=60)
            self.rest = out or ""
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, 9)
            self.proc.wait()
            raise AssertionError("tuilaunch serve did not stop on Ctrl+C") from None
        return int(self.proc.returncode)

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, 9)
            except ProcessLookupError:
                pass
            self.proc.wait()
        self.errors()
        self.err.unlink(missing_ok=True)


def tab_processes(runtime: Path, waiting: bool = False) -> list[int]:
    """The `tuilaunch attach` processes serve runs for its tabs, of this test's sessions
    (their XDG_RUNTIME_DIR is the test's): found even once serve is gone. A tab's process
    started ahead (cli/serve_tab.py) is named `tuilaunch-tab` once a page took it, and
    `tuilaunch-warm` while it waits (counted with `waiting`)."""
    mark = f"XDG_RUNTIME_DIR={runtime}".encode()
    names = ("tuilaunch-tab", "tuilaunch-warm") if waiting else ("tuilaunch-tab",)
    return [pid for pid in proc_tree.pids() if alive(pid)
            and (b"\0attach\0" in proc_tree.cmdline(pid) or process_name(pid) in names)
            and mark in proc_tree.environ(pid).split(b"\0")]


def process_name(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        return ""
