"""A lost link's reason fitted to a status line: its end (what failed) is kept."""

from tuilaunch.client.link import short_reason

REFUSED = "cannot reach robot1: connect to host 127.0.0.1 port 51697: Connection refused"


def test_a_reason_that_fits_is_kept_whole() -> None:
    assert short_reason(REFUSED, 80) == REFUSED
    assert short_reason("ssh exit status 255", 19) == "ssh exit status 255"


def test_a_long_reason_keeps_what_failed_and_its_end() -> None:
    assert short_reason(REFUSED, 50) == "cannot reach robot1: … Connection refused"
    assert short_reason(REFUSED, 25) == "… Connection refused"
    assert short_reason(REFUSED, 10) == "…n refused"
    assert len(short_reason("no colon in this reason at all", 12)) == 12
