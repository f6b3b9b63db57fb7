#!/usr/bin/env python3
"""What tells a table top from a bed or sofa top: the distributions behind the table-top test.

  tests/bench/table_top_evidence.py CSV [CSV...] [--min-area 0.5]

Reads the CSVs of `findmug-eval --table-evidence FILE` (one per seed, run with the test off,
`--set tables.min_flat_share=0`, so that every cluster is there) and prints, per source and
true NYU-40 class (the most frequent one under the cluster's pixels), the 10th / 50th / 90th
percentiles of the measures, then every cluster with a top of at least --min-area m² (the
clusters the test looks at) with its flat share, sorted by it. Sources:

  truth          every true instance of the candidate classes clustered as if labelled table
                 (the same on every seed: counted once)
  predicted-all  every cluster of the model's table pixels, before the top-area and
                 horizontal filters
  detected       the tables findmug-eval found (what gets search positions)

flat_share is the test's measure (TableCluster::flat_share): of the top's points whose normal
is within 20 degrees of vertical, the share within 10 degrees.
"""
import argparse
import collections
import csv
import math

MEASURES = ["top_height_m", "length_m", "width_m", "top_area_m2", "band_spread_m",
            "band_flat_share", "median_tilt_deg", "tilt10_share", "tilt20_share", "flat_share",
            "under_filled_share"]


def percentile(values, p):
    values = sorted(v for v in values if not math.isnan(v))
    if not values:
        return float("nan")
    return values[min(len(values) - 1, int(p * len(values)))]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("csv", nargs="+")
    p.add_argument("--min-area", type=float, default=0.5)
    args = p.parse_args()
    rows, seen = [], set()
    for path in args.csv:
        with open(path) as f:
            for r in csv.DictReader(f):
                if r["source"] == "truth":
                    key = (r["frame"], r["nyu40"], r["points"])
                    if key in seen:
                        continue
                    seen.add(key)
                r["file"] = path
                rows.append(r)
    for source in ("truth", "predicted-all", "detected"):
        groups = collections.defaultdict(list)
        for r in rows:
            if r["source"] == source:
                groups[r["nyu40"]].append(r)
        print(f"## {source}: 10th / 50th / 90th percentile per true class\n")
        print("| class | n | " + " | ".join(MEASURES) + " |")
        print("|---|---:|" + "---|" * len(MEASURES))
        for cls, members in sorted(groups.items(), key=lambda g: -len(g[1])):
            cells = []
            for m in MEASURES:
                v = [float(r[m]) for r in members]
                cells.append(" / ".join(f"{percentile(v, q):.2f}" for q in (0.1, 0.5, 0.9)))
            print(f"| {cls} | {len(members)} | " + " | ".join(cells) + " |")
        print()
    print(f"## clusters with a top of at least {args.min_area} m², by flat share\n")
    print("| source | file | frame | true class (share) | top height m | top area m² | flat share |")
    print("|---|---|---|---|---:|---:|---:|")
    large = [r for r in rows if r["source"] != "detected" and float(r["top_area_m2"]) >= args.min_area]
    for r in sorted(large, key=lambda r: float(r["flat_share"]) if r["flat_share"] != "nan" else 9):
        print(f"| {r['source']} | {r['file']} | {r['frame']} | {r['nyu40']} "
              f"({float(r['nyu40_share']):.2f}) | {float(r['top_height_m']):.2f} | "
              f"{float(r['top_area_m2']):.2f} | {float(r['flat_share']):.3f} |")


if __name__ == "__main__":
    main()
