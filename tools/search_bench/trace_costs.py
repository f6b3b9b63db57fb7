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

With --rooms (traces that name the rooms, "room N (KIND): (X, Y) to (X, Y)", and the mug's
room on the first line): the time of each decision counted to the room it was about (a room
explored, a search position's room, a look-around's room) against the mug's room: the start's
look-around, other rooms, the mug's room, covering at the end; medians over the episodes,
and how many spent no time on another room before the find. With --episodes EPISODES_CSV
(the run's episodes.csv, with the oracle strategy) also the median per episode of the search
time over the oracle's, as it is and without the time on other rooms (and the start's
look-around): what a search that knew the mug's room would still take.

Usage: trace_costs.py [--budget S] [--run PREFIX] [--rooms [--episodes CSV]] TRACE_DIR
Prints, per category, the seconds per episode (mean), the share of all search time, and for
table visits the number of visits and how many of them were on a real table.
"""
import argparse
import pathlib
import csv
import re
import statistics
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


ROOM = re.compile(r"^room (\d+) \([a-z ]+\): \(([-0-9.]+), ([-0-9.]+)\) to \(([-0-9.]+), ([-0-9.]+)\)$")
POSE = re.compile(r"^\s*[0-9.]+ s\s+\(\s*([-0-9.]+),\s*([-0-9.]+)\)")


def room_costs(path, budget):
    """Seconds of one trace on the start's look-around, other rooms, the mug's room, covering."""
    rooms, mug_room, segments = {}, None, []
    end = budget

    def room_at(x, y):
        for k, (lx, ly, hx, hy) in rooms.items():
            if lx <= x <= hx and ly <= y <= hy:
                return k
        return -1

    for raw in path.read_text().splitlines()[1:]:
        m = LINE.match(raw)
        if not m:
            raise ValueError(f"{path}: not a trace line: {raw!r}")
        t, what = float(m.group(1)), m.group(2)
        x, y = (float(v) for v in POSE.match(raw).groups())
        r = ROOM.match(what)
        if r:
            rooms[int(r.group(1))] = tuple(float(r.group(i)) for i in range(2, 6))
            continue
        mug = re.match(r"the mug at .* room (-?\d+)$", what)
        if mug:
            mug_room = int(mug.group(1))
            continue
        if what.startswith("found") or what.startswith("false found"):
            end = t
            break
        if what.startswith("look around"):
            if segments and segments[-1][1] == "cover":
                continue  # coverage looks around at each of its goals
            kind = "start" if not segments else ("mug" if room_at(x, y) == mug_room else "other")
        elif what.startswith("explore room"):
            kind = "mug" if int(what.split()[2]) == mug_room else "other"
        elif what.startswith("search position of table"):
            p = re.search(r"\(([-0-9.]+), ([-0-9.]+)\)", what)
            kind = "mug" if room_at(float(p.group(1)), float(p.group(2))) == mug_room else "other"
        elif what.startswith("cover the floor plan") or what.startswith("look at the furniture"):
            kind = "cover"
        else:
            continue
        segments.append((t, kind))
    if not rooms or mug_room is None:
        raise ValueError(f"{path}: no room lines (--rooms needs traces that name the rooms)")
    costs = dict.fromkeys(["start", "other", "mug", "cover"], 0.0)
    for i, (t, kind) in enumerate(segments):
        costs[kind] += (segments[i + 1][0] if i + 1 < len(segments) else end) - t
    return costs, end


def print_rooms(files, budget, episodes_csv):
    runs = [room_costs(f, budget) for f in files]
    costs = [c for c, _ in runs]
    print(f"{len(files)} episodes, time per decision's room (median; mean)")
    print("| about | s per episode, median | mean |")
    print("|---|---|---|")
    names = {"start": "the start's look-around", "other": "rooms other than the mug's",
             "mug": "the mug's room", "cover": "covering at the end, the grid's furniture"}
    for k, name in names.items():
        v = [c[k] for c in costs]
        print(f"| {name} | {statistics.median(v):.1f} | {statistics.mean(v):.1f} |")
    print(f"episodes with no time on another room: {sum(c['other'] == 0 for c in costs)}")
    if not episodes_csv:
        return
    oracle = {}
    with open(episodes_csv) as f:
        for row in csv.DictReader(f):
            if row["strategy"] == "oracle":
                t = float(row["time_s"]) if row["found"] == "1" else budget
                oracle[(row["apartment"], row["episode"])] = t
    ratios = []
    for path, (c, end) in zip(files, runs):
        m = re.search(r"_a(\d+)_e(\d+)\.txt$", path.name)
        key = (m.group(1), m.group(2))
        if key not in oracle:
            raise ValueError(f"{episodes_csv}: no oracle row for episode {key[0]}.{key[1]}")
        o = max(1e-3, oracle[key])
        ratios.append((end / o, (end - c["other"]) / o, (end - c["other"] - c["start"]) / o))
    print("median per episode, search time over the oracle's: "
          f"{statistics.median(r[0] for r in ratios):.2f}; without other rooms "
          f"{statistics.median(r[1] for r in ratios):.2f}; without them and the start's "
          f"look-around {statistics.median(r[2] for r in ratios):.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace_dir")
    ap.add_argument("--budget", type=float, default=600.0)
    ap.add_argument("--run", default="findmug-", help="trace file name prefix (the run label)")
    ap.add_argument("--rooms", action="store_true",
                    help="the time per room a decision was about, against the mug's room")
    ap.add_argument("--episodes", help="with --rooms: the run's episodes.csv (oracle times)")
    a = ap.parse_args()
    files = sorted(pathlib.Path(a.trace_dir).glob(a.run + "*.txt"))
    if not files:
        sys.exit(f"trace_costs: no trace files {a.run}*.txt in {a.trace_dir}")
    if a.rooms:
        try:
            print_rooms(files, a.budget, a.episodes)
        except ValueError as e:
            sys.exit(f"trace_costs: {e}")
        return
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
