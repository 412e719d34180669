"""Shared formatting of the benchmark table scripts (bench_*_table.py): times, ratios, counts,
and a Markdown table. Standard library only."""
import math


def fmt_time(s):
    if s is None or not math.isfinite(s):
        return "-"
    if s < 1e-3:
        return f"{s * 1e6:.0f} us"
    if s < 1.0:
        return f"{s * 1e3:.1f} ms"
    if s < 100.0:
        return f"{s:.2f} s"
    return f"{s:.0f} s"


def fmt_ratio(r):
    return "-" if r is None or not math.isfinite(r) else f"{r:.1f}x"


def fmt_int(v):
    return "-" if v is None else str(int(round(v)))


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)
