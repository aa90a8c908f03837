"""Rates, sizes and CPU as short texts of stable width: a cell that changes width would
make its table re-lay out, and every change is bytes over ssh."""

from __future__ import annotations

from typing import Any


def rate_text(rate_hz: Any) -> str:
    """`10.0 Hz`, `1.25 kHz`; `-` when nothing was measured."""
    if not isinstance(rate_hz, (int, float)):
        return "-"
    if rate_hz >= 1000:
        return f"{rate_hz / 1000:.2f} kHz"
    if rate_hz >= 100:
        return f"{rate_hz:.0f} Hz"
    return f"{rate_hz:.1f} Hz"


def bytes_text(count: Any, suffix: str = "") -> str:
    """`340 B`, `1.2 KB`, `12.3 MB` (powers of 1024, as top and htop count)."""
    if not isinstance(count, (int, float)):
        return "-"
    value = float(count)
    for unit in ("B", "KB", "MB", "GB"):
        if value < 1024 or unit == "GB":
            return f"{value:.0f} {unit}{suffix}" if unit == "B" else \
                f"{value:.1f} {unit}{suffix}"
        value /= 1024
    return "-"  # unreachable: GB ends the loop


def short_bytes(count: Any) -> str:
    """A tree row's memory in at most 5 characters: `812K`, `45M`, `1.2G`."""
    if not isinstance(count, (int, float)):
        return ""
    value = float(count)
    for unit in ("B", "K", "M", "G"):
        if value < 1000 or unit == "G":
            return f"{value:.1f}{unit}" if unit == "G" and value < 10 else f"{value:.0f}{unit}"
        value /= 1024
    return ""


def usage_text(usage: dict[str, Any]) -> str:
    """A process's CPU, memory and threads for the detail line."""
    parts = []
    cpu = usage.get("cpu_percent")
    if isinstance(cpu, (int, float)):
        parts.append(f"cpu {cpu:.0f}%")
    rss = usage.get("rss_bytes")
    if isinstance(rss, (int, float)):
        parts.append(f"mem {bytes_text(rss)}")
    threads = usage.get("threads")
    if isinstance(threads, int):
        parts.append(f"{threads} threads")
    if usage.get("growing"):
        parts.append("memory keeps growing")
    return ", ".join(parts)


BARS = "▁▂▃▄▅▆▇█"


def spark(data: list[float], width: int) -> str:
    """`data` as a sparkline `width` bars wide (each bar the max of its share of the
    samples; fewer samples than bars are stretched, as Textual's Sparkline does), from a
    zero baseline to the largest value: a steady rate is a steady row of full bars (not
    nothing, as scaled between its own min and max), 10 % beside 12 % CPU nearly the same
    height. Say the scale beside it (its max)."""
    if not data or width < 1:
        return ""
    n = len(data)
    shares = [max(data[i * n // width:max((i + 1) * n // width, i * n // width + 1)])
              for i in range(width)]
    high = max(shares)
    if high <= 0:
        return BARS[0] * width
    top = len(BARS) - 1
    return "".join(BARS[max(0, min(top, round(v / high * top)))] for v in shares)
