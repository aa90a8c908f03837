"""Lines kept whole up to 8 MiB stay within bounds on their way: a display's buffer holds a
bounded amount of text, a batch is spread over messages the other side can read, and a
`read_log` answer pages on rather than outgrow a message."""

from __future__ import annotations

from tuilaunch.engine.run.event_buffer import EventBuffer
from tuilaunch.engine.run.events import Output, Started
from tuilaunch.engine.run.session.clients import in_messages
from tuilaunch.engine.run.session.log_reader import read_log
from tuilaunch.engine.run.session.protocol import MESSAGE_TEXT


def test_a_display_buffer_holds_a_bounded_text_and_counts_what_it_dropped():
    for fair in (False, True):
        buffer = EventBuffer(max_lines=1000, fair=fair, max_bytes=10_000)
        buffer(Started("a", pid=1))
        for i in range(50):
            buffer(Output(f"p{i % 3}", stream="stdout", lines=["x" * 900, "y" * 900]))
        events = buffer.drain()
        lines = [line for e in events if isinstance(e, Output) for line in e.lines]
        dropped = sum(e.code or 0 for e in events if e.kind == "dropped")
        assert sum(map(len, lines)) <= 10_000 and len(lines) + dropped == 100
        assert any(isinstance(e, Started) for e in events)  # never dropped


def test_a_batch_of_long_lines_is_spread_over_messages_in_order():
    events = [Started("a", pid=1),
              Output("a", stream="stdout", lines=["x" * 4, "y" * 4, "z" * 4]),
              Started("b", pid=2), Output("b", stream="stdout", lines=["w" * 20])]
    parts = in_messages(events, budget=9)
    assert [[(e.kind, e.lines) for e in part] for part in parts] == [
        [("started", []), ("output", ["xxxx", "yyyy"])],
        [("output", ["zzzz"]), ("started", [])],
        [("output", ["w" * 20])]]  # a line longer than the budget goes alone, whole
    assert in_messages(events) == [events]  # the usual batch: one message


def test_read_log_pages_long_lines_by_the_message_budget(tmp_path):
    path = tmp_path / "long-1.log"
    with open(path, "wb") as handle:
        for i in range(20):
            handle.write(b"1.0 stdout %02d" % i + b"z" * (1 << 20) + b"\n")
    texts, start = [], 0
    while True:
        page = read_log(path, start=start)
        size = sum(len(line[2]) for line in page["lines"])
        assert size <= MESSAGE_TEXT and page["lines"]
        texts += [line[2] for line in page["lines"]]
        if page["next"] >= page["size"]:
            break
        start = int(page["next"])
    assert [text[:2] for text in texts] == [f"{i:02d}" for i in range(20)]
    assert all(len(text) == 2 + (1 << 20) for text in texts)
    tail = read_log(path, tail=True, limit=100)["lines"]
    assert [line[2][:2] for line in tail] == [f"{i:02d}" for i in range(20 - len(tail), 20)]
    assert sum(len(line[2]) for line in tail) <= MESSAGE_TEXT
