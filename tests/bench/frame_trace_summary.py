#!/usr/bin/env python3
"""frame_trace_summary.py — where a daemon run's latency went, from findmugd's frame trace.

    tests/bench/frame_trace_summary.py TRACE.csv [--label TEXT]

TRACE.csv is what daemon.frame_trace_file writes (frame_trace.hpp): one row per published
frame, microseconds per interval. Prints one Markdown table row: for every interval, the
p50 / p99 / max in ms, then the same for the frames whose total latency is in the top 1 %
(what the tail is made of). tests/bench/daemon_bench.sh calls it for every threaded run.
"""
import argparse
import csv
import math
import sys

INTERVALS = ["source", "door", "prepare", "segment_wait", "segment", "reorder", "publish_wait",
             "publish", "total"]


def rank(sorted_values, q):
    """Nearest-rank percentile (as the daemon's own LatencyWindow)."""
    if not sorted_values:
        return float("nan")
    idx = max(1, min(len(sorted_values), math.ceil(q * len(sorted_values))))
    return sorted_values[idx - 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trace")
    parser.add_argument("--label", default="")
    args = parser.parse_args()
    try:
        with open(args.trace, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"frame_trace_summary: {args.trace}: {e.strerror}")
    missing = [c for c in INTERVALS if c + "_us" not in (rows[0].keys() if rows else INTERVALS)]
    if missing:
        sys.exit(f"frame_trace_summary: {args.trace}: no column(s) {', '.join(missing)}")
    if not rows:
        print(f"| {args.label} | 0 |" + " - |" * len(INTERVALS))
        return
    # The slowest 1 % of frames (at least one): what each interval contributed to the tail.
    by_total = sorted(rows, key=lambda r: int(r["total_us"]))
    tail = by_total[-max(1, len(rows) // 100):]
    cells = []
    for name in INTERVALS:
        values = sorted(int(r[name + "_us"]) / 1000.0 for r in rows if int(r[name + "_us"]) >= 0)
        tail_values = [int(r[name + "_us"]) / 1000.0 for r in tail if int(r[name + "_us"]) >= 0]
        tail_mean = sum(tail_values) / len(tail_values) if tail_values else float("nan")
        cells.append(f"{rank(values, 0.5):.0f} / {rank(values, 0.99):.0f} / {values[-1]:.0f} "
                     f"({tail_mean:.0f})" if values else "-")
    print(f"| {args.label} | {len(rows)} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
