"""`tuilaunch serve A B`: the fleet view of two sessions at one URL, in a real browser
(Debian's chromium, driven by Selenium): both roots on the page at 1100x700, 1024x768 and
390x844; `}` reaches the second session's root and `s` on a node there stops it alone; at
1024x768 a tap (a click at the cell) on a row selects it, the footer shows the single TUI's
node keys whole (Type, Debug, the tabs, Stop, Restart, Start, Search), a tap on its Stop
stops the node, w hands the pane to the browser as a download (fetched once), and a tap on
its Type asks, in the page itself, to start the stopped node (run with pipes) with a
terminal, naming its session (No leaves it); the page of `serve` alone links each session
and the whole fleet.
"""

from __future__ import annotations

import urllib.error
import urllib.request

import pytest

from ..conftest import wait_for
from .browser import Serving, free_port, page, tab_processes
from .test_serve import states
from .test_sessions import runtime, start_detached, tl  # noqa: F401

pytestmark = pytest.mark.timeout(900)

TABLET_KEYS = (("i", "Type"), ("g", "Debug"), ("1", "Nodes"), ("2", "Args"),
               ("3", "Services"), ("4", "Params"), ("s", "Stop"), ("r", "Restart"),
               ("t", "Start"), ("/", "Search"))
"""The keys a tablet's footer (1024x768) shows whole in the fleet view, as the single
TUI's does."""


def test_serve_of_two_sessions_is_one_fleet_page(runtime, write):  # noqa: F811
    first = start_detached(write, "--name", "nuc")
    second = start_detached(write, "--name", "arm")
    serving = Serving(first, second, "--port", str(free_port()))
    try:
        # (wait_for returns nothing: it fails by itself when the line never comes)
        wait_for(lambda: "the fleet view of nuc arm" in serving.errors(), what="serve says what")
        with page() as browser:
            for width, height in ((1100, 700), (1024, 768), (390, 844)):
                browser.driver.set_window_size(width, height)
                browser.open(serving.url)
                browser.wait_screen(lambda t: "▼ local:nuc  2 running" in t and
                                    "▼ local:arm  2 running" in t,
                                    f"both roots at {width}x{height}")
            browser.driver.set_window_size(1100, 700)
            browser.open(serving.url)
            browser.wait_screen(lambda t: "local:arm" in t and "echo-3" in t, "both trees")
            browser.type("}")  # arm's root
            browser.wait_screen(lambda t: "[local:arm]" in t, "arm selected")
            browser.type("\ue015\ue015")  # down past all nodes to arm's ticker
            text = browser.wait_screen(lambda t: t.splitlines()[3].strip().startswith(
                "ticker-1"), "arm's ticker-1 selected")
            assert "[local:arm]" in text
            browser.type("s")
            wait_for(lambda: states(second)["ticker-1"] == "exited", what="arm's ticker stopped")
            assert states(first)["ticker-1"] == "running"  # nuc's: untouched
        # a tablet: a tap on a row selects it, a tap on the footer's Stop stops it, and w
        # hands the pane to the browser as a download
        with page() as browser:
            browser.catch_downloads()
            browser.driver.set_window_size(1024, 768)
            browser.open(serving.url)
            text = browser.wait_screen(lambda t: "local:nuc" in t and "echo-3" in t,
                                       "both trees at 1024x768")
            row = next(i for i, line in enumerate(text.splitlines()) if "echo-3" in line)
            browser.tap("echo-3", row)  # nuc's echo-3: the first tree's
            browser.wait_screen(lambda t: t.splitlines()[3].strip().startswith("echo-3") and
                                "[local:nuc]" in t, "nuc's echo-3 selected by a tap")
            # a browser's footer is compact (cli/serve_tab.py): the single TUI's keys whole,
            # each a tap away
            footer = browser.wait_screen(lambda t: all(
                f"{key} {word} " in t.splitlines()[-1] for key, word in TABLET_KEYS),
                "the node's keys and the tabs whole in the footer")
            browser.tap("Stop", len(footer.splitlines()) - 1)
            wait_for(lambda: states(first)["echo-3"] == "exited",
                     what="nuc's echo-3 stopped by a tap on Stop")
            assert states(second)["echo-3"] == "running"
            browser.type("w")
            wait_for(lambda: browser.opened(), what="the pane handed to the browser")
            with urllib.request.urlopen(browser.opened()[0], timeout=30) as got:
                # the selected node's pane, as w saves it in a terminal
                assert 'attachment; filename="echo-3-pane-' in \
                    got.headers["Content-Disposition"]
                assert got.read().decode().endswith("\n")
            with pytest.raises(urllib.error.HTTPError):  # each is fetched once
                urllib.request.urlopen(browser.opened()[0], timeout=30)
            # a tap on Type: the fleet types into the node itself (a page cannot hand its
            # terminal to another TUI); the stopped echo-3 is offered a start with one
            browser.tap("Type", len(footer.splitlines()) - 1)
            browser.wait_screen(lambda t: "echo-3 of local:nuc has no terminal to type "
                                "into" in " ".join(t.split()) and "Start it with a terminal"
                                in " ".join(t.split()),
                                "the question, in the page, naming the session")
            browser.tap("No (n)")
            browser.wait_screen(lambda t: "Start it with" not in t and "[local:nuc]" in t,
                                "the question answered")
            assert states(first)["echo-3"] == "exited"  # no: left as it was
    finally:
        serving.close()
    # serve alone: a page linking each session and all of them together
    listing = Serving("--port", str(free_port()))
    try:
        with page() as browser:
            browser.open(listing.url)
            source = browser.driver.page_source
            assert "href=\"s/nuc/\"" in source and "href=\"s/arm/\"" in source
            assert "href=\"fleet/\"" in source
            browser.open(listing.url.rstrip("/") + "/fleet/")
            browser.wait_screen(lambda t: "local:nuc" in t and "local:arm" in t,
                                "the fleet of every session")
    finally:
        listing.close()
    wait_for(lambda: not tab_processes(runtime), what="no tab's TUI left")
    for name in (first, second):
        tl("stop", name)
