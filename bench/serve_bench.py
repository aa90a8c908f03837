"""`tuilaunch serve` figures, one run on this machine, each beside its terminal counterpart.

With the demo (examples/bringup.py) running as a session on "robot1" (a real sshd on
127.0.0.1, from tests/integration/sshd.py) and `tuilaunch serve` on it:

1. Time to the tree: from opening the URL in Debian's chromium (headless, driven by
   Selenium, a fresh profile each time; once serve's process started ahead of the next tab
   is there, cli/serve_tabs.py) until the page's terminal shows a node of the tree
   (read from xterm.js's own screen), beside `tuilaunch attach NAME` in a pseudo-terminal:
   from its start until its first frame shows the same node. Median of 3.
2. Bytes per second crossing TCP for one tab at 80x24 (a websocket client asking for
   permessage-deflate, as browsers do, through a counting relay), idle and under a flood
   of 2,000 lines a second; beside, in the same run, `tuilaunch attach robot1:NAME` (the
   session protocol over ssh) and the TUI drawn over `ssh -t` and `ssh -C -t`
   (bench/remote_bench.py's measure, the same counting relay).
3. Memory (RSS) of each served tab's process (`tuilaunch attach` under the web driver),
   beside the same attach in a terminal.

With `--fleet`, instead: `tuilaunch serve robot1:fleet-1 ... robot1:fleet-N` (the fleet
view at one URL, each session the demo over its own ssh link) for N = 2 and 4: the time to
the first tree in chromium, the bytes per second of one page (TCP, idle, once settled) and
the RSS of its tab's process, beside `tuilaunch attach` of the same sessions in a terminal.

    python bench/serve_bench.py [--fleet]
"""

from __future__ import annotations

import asyncio
import json
import os
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from remote_bench import FLOOD_CODE, FLOODER, Link, measure, start_session  # noqa: E402
from tui_bench import Terminal  # noqa: E402  (bench/ is on sys.path as a script)

from tests.integration.browser import (  # noqa: E402
    Page,
    free_port,
    need_chromium,
    process_name,
)
from tests.integration.proc_tree import cmdline, descendants  # noqa: E402
from tests.integration.sshd import Machines  # noqa: E402

WINDOW = 10.0
SETTLE = 5.0
MARKER = "talker-1"


class Served:
    """`tuilaunch serve NAME ...` with robot1's session folder; its URL."""

    def __init__(self, name: str, env: dict[str, str], *more: str) -> None:
        self.port = free_port()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "tuilaunch", "serve", name, *more, "--port",
             str(self.port)],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env,
            start_new_session=True)
        assert self.proc.stdout is not None
        self.url = self.proc.stdout.readline().strip()

    def tabs(self) -> list[int]:
        return [p for p in descendants(self.proc.pid) if b"\0attach\0" in cmdline(p)
                or process_name(p) == "tuilaunch-tab"]  # not the one waiting

    def ready(self) -> Served:
        """Once serve's process started ahead of the next tab is there (as it is for a
        user opening the URL of a serve that ran a few seconds): the open is measured
        from there."""
        end = time.perf_counter() + 60
        while time.perf_counter() < end and not any(
                process_name(p) == "tuilaunch-warm" for p in descendants(self.proc.pid)):
            time.sleep(0.2)
        time.sleep(1.0)  # its imports: a second or two on a quiet machine
        return self

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGINT)
        self.proc.wait(timeout=60)


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def page_to_tree(url: str) -> float:
    page = Page()
    try:
        start = time.perf_counter()
        page.open(url)
        page.wait_screen(lambda text: MARKER in text, "the tree", timeout=120)
        return time.perf_counter() - start
    finally:
        page.close()


def terminal_to_tree(name: str, env: dict[str, str], *more: str) -> tuple[float, float]:
    """Seconds to the first frame showing the tree, and the attach's RSS once settled."""
    saved = dict(os.environ)
    os.environ.update(env)
    try:
        start = time.perf_counter()
        term = Terminal([sys.executable, "-m", "tuilaunch", "attach", name, *more],
                        size=(80, 24))
    finally:
        os.environ.clear()
        os.environ.update(saved)
    try:
        term.read_until(MARKER.encode(), limit=120)
        elapsed = time.perf_counter() - start
        term.settle(SETTLE)
        return elapsed, rss_mb(term.proc.pid)
    finally:
        term.close(b"q" if more else b"d")  # a fleet view leaves with q (its sessions run on)


async def relay_bytes(port: int, ws_path: str) -> tuple[float, float, float]:
    """One tab through a counting TCP relay: (bytes/s both ways over WINDOW once settled,
    bytes/s of websocket payload from the server, the first frame's seconds)."""
    import aiohttp

    counted = [0]

    async def pipe(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while data := await reader.read(1 << 16):
                counted[0] += len(data)
                writer.write(data)
                await writer.drain()
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            writer.close()

    async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        upstream_reader, upstream_writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            await asyncio.gather(pipe(reader, upstream_writer), pipe(upstream_reader, writer))
        except asyncio.CancelledError:
            pass  # the relay closes with the measure

    relay = await asyncio.start_server(handle, "127.0.0.1", 0)
    relay_port = relay.sockets[0].getsockname()[1]
    payload = 0
    async with aiohttp.ClientSession() as client, client.ws_connect(
            f"ws://127.0.0.1:{relay_port}{ws_path}?width=80&height=24",
            headers={"Origin": f"http://127.0.0.1:{relay_port}"}, compress=15) as ws:
        start = time.perf_counter()
        first = 0.0

        async def read_for(seconds: float) -> int:
            nonlocal first
            got = 0
            end = time.perf_counter() + seconds
            while (left := end - time.perf_counter()) > 0:
                try:
                    message = await asyncio.wait_for(ws.receive(), left)
                except TimeoutError:
                    break
                if message.type == aiohttp.WSMsgType.BINARY:
                    got += len(message.data)
                    if not first and MARKER.encode() in message.data:
                        first = time.perf_counter() - start
                elif message.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED):
                    break
            return got

        await read_for(SETTLE)
        before = counted[0]
        payload = await read_for(WINDOW)
        wire = (counted[0] - before) / WINDOW
        await ws.send_json(["stdin", "q"])  # the tab leaves, the launch runs on
        await read_for(2.0)
    relay.close()
    return wire, payload / WINDOW, first


def fleet(machines: Machines, env: dict[str, str], link: Link) -> None:
    """`--fleet`: the fleet view served, of 2 and of 4 sessions over ssh (see the module)."""
    bringup = ROOT / "examples" / "bringup.py"
    names = [f"fleet-{i}" for i in range(1, 5)]
    remote = f"{shlex.quote(sys.executable)} -m tuilaunch"
    ssh_env = {**env, "TUILAUNCH_SSH_COMMAND": link.ssh("fleet"), "TUILAUNCH_REMOTE": remote}
    rows = {}
    try:
        for name in names:
            start_session(machines, bringup, name)
        for count in (2, 4):
            addresses = [f"robot1:{n}" for n in names[:count]]
            served = Served(addresses[0], ssh_env, *addresses[1:])
            try:
                pages = [page_to_tree(served.ready().url) for _ in range(3)]
                terminals = [terminal_to_tree(addresses[0], ssh_env, *addresses[1:])
                             for _ in range(3)]
                wire, payload, _ = asyncio.run(relay_bytes(served.port, "/ws"))
                rss = asyncio.run(tab_memory(served, served.url.rstrip("/")))
            finally:
                served.stop()
            rows[count] = {"page_to_tree": statistics.median(pages),
                           "terminal_to_tree": statistics.median(t[0] for t in terminals),
                           "bytes_per_s_tcp": wire, "bytes_per_s_payload": payload,
                           "tab_rss_mb": rss,
                           "terminal_rss_mb": statistics.median(t[1] for t in terminals)}
            print(count, rows[count], flush=True)
    finally:
        for name in names:
            subprocess.run([sys.executable, "-m", "tuilaunch", "stop", name], env=env,
                           capture_output=True)
    print("the fleet view served (the demo, each session over its own ssh link), 80x24 tab")
    print(f"  {'sessions':>8}{'page->tree':>12}{'attach->tree':>14}{'bytes/s idle':>14}"
          f"{'tab RSS':>10}{'attach RSS':>12}")
    for count, row in rows.items():
        print(f"  {count:>8}{row['page_to_tree']:>11.2f}s{row['terminal_to_tree']:>13.2f}s"
              f"{row['bytes_per_s_tcp']:>14,.0f}{row['tab_rss_mb']:>8.1f}MB"
              f"{row['terminal_rss_mb']:>10.1f}MB")
    print(json.dumps(rows))


def main() -> None:
    from tuilaunch.engine.packages import ensure_environment

    ensure_environment()
    need_chromium_or_exit()
    folder = Path(tempfile.mkdtemp(prefix="tlserve"))
    machines = Machines(folder / "ssh", aliases=("robot1",))
    robot = machines["robot1"]
    env = {**os.environ, "XDG_RUNTIME_DIR": str(robot.runtime),
           "ROS_LOG_DIR": str(robot.folder / "roslog")}
    remote = f"{shlex.quote(sys.executable)} -m tuilaunch"
    link = Link(machines, folder, robot.port)
    bringup = ROOT / "examples" / "bringup.py"
    if "--fleet" in sys.argv[1:]:
        try:
            fleet(machines, env, link)
        finally:
            machines.stop()
        return
    flood = folder / "flood_launch.py"
    flood.write_text(bringup.read_text().replace(
        "\n    return sl.launch_description()\n",
        FLOODER.format(python=sys.executable, code=FLOOD_CODE)))
    results: dict[str, object] = {}
    try:
        start_session(machines, bringup, "demo")
        served = Served("demo", env)
        origin = served.url.rstrip("/")
        pages = [page_to_tree(served.ready().url) for _ in range(3)]
        terminals = [terminal_to_tree("demo", env) for _ in range(3)]
        results["to_tree"] = {"page": statistics.median(pages),
                              "terminal": statistics.median(t[0] for t in terminals),
                              "pages": pages, "terminals": [t[0] for t in terminals]}
        # memory: one tab open (a websocket client), its process's RSS once settled
        tab_rss = asyncio.run(tab_memory(served, origin))
        results["memory_mb"] = {"tab": tab_rss,
                                "terminal": statistics.median(t[1] for t in terminals)}
        print(json.dumps(results), flush=True)  # so far, should a later part fail
        rows = {}
        for name, session, path in (("demo", "demo", None), ("flood", "flood", flood)):
            if path is not None:
                start_session(machines, path, session)
                served.stop()
                served = Served(session, env)
                origin = served.url.rstrip("/")
            wire, payload, _first = asyncio.run(relay_bytes(served.port, "/ws"))
            marker = b"says hi" if session == "demo" else b"of the lidar"
            ours = measure([sys.executable, "-m", "tuilaunch", "attach", f"robot1:{session}"],
                           {"TUILAUNCH_SSH_COMMAND": link.ssh(f"ours-{name}"),
                            "TUILAUNCH_REMOTE": remote}, link, f"ours-{name}", marker)
            drawn = measure([*shlex.split(link.ssh(f"drawn-{name}")), "-t", "robot1",
                             f"{remote} attach {session}"], {}, link, f"drawn-{name}", marker)
            squeezed = measure([*shlex.split(link.ssh(f"drawnc-{name}")), "-C", "-t",
                                "robot1", f"{remote} attach {session}"], {}, link,
                               f"drawnc-{name}", marker)
            print(name, wire, payload, ours, drawn, squeezed, flush=True)
            rows[name] = {"websocket_tcp": wire, "websocket_payload": payload,
                          "attach_over_ssh": ours[1], "ssh_t": drawn[1],
                          "ssh_C_t": squeezed[1]}
        results["bytes_per_s"] = rows
        served.stop()
    finally:
        for session in ("demo", "flood"):
            subprocess.run([sys.executable, "-m", "tuilaunch", "stop", session], env=env,
                           capture_output=True)
        machines.stop()
    to_tree = results["to_tree"]
    print("time to the tree, 80x24 terminal / 1100x700 browser window (median of 3)")
    print(f"  page (open the URL -> tree in xterm.js)  {to_tree['page']:.2f} s")  # type: ignore[index]
    print(f"  terminal (attach -> first frame)         {to_tree['terminal']:.2f} s")  # type: ignore[index]
    print("bytes/s, one client at 80x24, once settled")
    print(f"  {'':18}{'serve tab (TCP)':>16}{'attach over ssh':>17}{'ssh -t':>10}"
          f"{'ssh -C -t':>11}")
    for name, row in rows.items():
        label = {"demo": "demo, idle", "flood": "demo + 2,000 l/s"}[name]
        print(f"  {label:18}{row['websocket_tcp']:>16,.0f}{row['attach_over_ssh']:>17,.0f}"
              f"{row['ssh_t']:>10,.0f}{row['ssh_C_t']:>11,.0f}")
    memory = results["memory_mb"]
    print(f"memory: a served tab's process {memory['tab']:.1f} MB RSS, "  # type: ignore[index]
          f"attach in a terminal {memory['terminal']:.1f} MB")  # type: ignore[index]
    print(json.dumps(results))


async def tab_memory(served: Served, origin: str) -> float:
    import aiohttp

    async with aiohttp.ClientSession() as client, client.ws_connect(
            served.url.replace("http", "ws", 1) + "ws?width=80&height=24",
            headers={"Origin": origin}) as ws:
        end = time.perf_counter() + 20
        while time.perf_counter() < end and not served.tabs():
            await asyncio.sleep(0.1)
        settle = time.perf_counter() + SETTLE + 5
        while time.perf_counter() < settle:
            try:
                await asyncio.wait_for(ws.receive(), 0.5)
            except TimeoutError:
                pass
        rss = sum(rss_mb(p) for p in served.tabs())
        await ws.send_json(["stdin", "q"])
        return rss


def need_chromium_or_exit() -> None:
    try:
        need_chromium()
    except BaseException as exc:  # pytest's skip outside pytest: say it and stop
        sys.exit(f"serve_bench: {exc}")


if __name__ == "__main__":
    main()
