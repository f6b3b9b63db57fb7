#!/usr/bin/env python3
"""Where the findmug strategy's search time goes, from findmug-search-bench --trace files.

Each trace line is "TIME s  (X, Y) YAW deg  WHAT". A line saying why the robot goes
somewhere starts a segment that lasts until the next such line or the end of the search:
  * "look around"                      -> look-around (at the start, or in a room)
  * "search position of table N ... truth KIND ..." -> visit of a mapped table whose
    centre stands on KIND in the ground truth (table, bed, sofa, cabinet, ..., nothing)
  * "explore room"                     -> exploring a room (driving to its centre)
  * "cover the floor plan"             -> covering what is left
  * "look at the furniture ..."        -> then every footprint of the grid from beside it
"drive to" and "stopped" lines belong to the segment they are in, and so do the look-arounds
of "cover the floor plan" (coverage looks around at each of its goals). The search ends at the
"found" line, else at the budget (--budget, default 600 s).

Usage: trace_costs.py [--budget S] [--run PREFIX] TRACE_DIR
Prints, per category, the seconds per episode (mean), the share of all search time, and for
table visits the number of visits and how many of them were on a real table.
"""
import argparse
import pathlib
import re
import sys
from collections import defaultdict

LINE = re.compile(r"^\s*([0-9.]+) s\s+\(\s*[-0-9.]+,\s*[-0-9.]+\)\s+-?[0-9]+ deg\s+(.*)$")


def category(what):
    if what.startswith("look around"):
        return "look-around"
    if what.startswith("search position of table"):
        m = re.search(r"truth ([a-z_?]+)", what)
        kind = m.group(1) if m else "?"
        return "visit: " + ("a real table" if kind == "table" else "false table on " + kind)
    if what.startswith("explore room"):
        return "explore a room"
    if what.startswith("cover the floor plan"):
        return "cover the floor plan"
    if what.startswith("look at the furniture"):
        return "the grid's furniture from beside it"
    return None


def episode_costs(path, budget):
    """Seconds per category of one trace, and whether the mug was found."""
    costs = defaultdict(float)
    visits = defaultdict(int)
    current, since = None, 0.0
    end, found = budget, False
    for raw in path.read_text().splitlines()[1:]:
        m = LINE.match(raw)
        if not m:
            raise ValueError(f"{path}: not a trace line: {raw!r}")
        t, what = float(m.group(1)), m.group(2)
        if what.startswith("found") or what.startswith("false found"):
            end, found = t, what.startswith("found")
            break
        c = category(what)
        if c is None:
            continue
        # Coverage looks around at every goal: its look-arounds and drives are covering.
        if current == "cover the floor plan" and c == "look-around":
            continue
        if current is not None:
            costs[current] += t - since
        current, since = c, t
        if c.startswith("visit"):
            visits[c] += 1
    if current is not None:
        costs[current] += max(0.0, end - since)
    return costs, visits, found, end


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace_dir")
    ap.add_argument("--budget", type=float, default=600.0)
    ap.add_argument("--run", default="findmug-", help="trace file name prefix (the run label)")
    a = ap.parse_args()
    files = sorted(pathlib.Path(a.trace_dir).glob(a.run + "*.txt"))
    if not files:
        sys.exit(f"trace_costs: no trace files {a.run}*.txt in {a.trace_dir}")
    total = defaultdict(float)
    visits = defaultdict(int)
    time_all = 0.0
    for f in files:
        costs, v, _, end = episode_costs(f, a.budget)
        for k, s in costs.items():
            total[k] += s
        for k, n in v.items():
            visits[k] += n
        time_all += end
    n = len(files)
    print(f"{n} episodes, {time_all / n:.1f} s of search per episode (mean)")
    print("| where the time went | s per episode | share | visits |")
    print("|---|---|---|---|")
    for k in sorted(total, key=lambda k: -total[k]):
        print(f"| {k} | {total[k] / n:.1f} | {100 * total[k] / time_all:.0f} % | "
              f"{visits.get(k, '') if k.startswith('visit') else ''} |")


if __name__ == "__main__":
    main()
