#!/usr/bin/env python3
"""BENCHMARKS.md section 1 in one command: every configuration row side by side on the same folds.

  tests/bench/accuracy_table.py [--build-dir build] [--data ../shared/data] [--out DIR]
                                [--seeds 3] [--paired-seeds 12] [--rows NAME,NAME...] [--jobs N]

Runs findmug-eval (5-fold cross-validation over the 46 shared labelled NYU frames, whole scenes
in a fold, ground from NYU's gravity) once per row and forest seed (42, 1042, 2042, ...) and
prints the markdown table of section 1: the mean and per-seed figures of the first --seeds
seeds, and, for rows run with --paired-seeds seeds, the class average against the row each one
is compared with and on how many seeds it is higher (a seed moves class average by 1-3 points
here, so one seed or one mean says little). Each run's JSON is kept in --out (default
accuracy-table/) as ROW-SEED.json and reused when present, so an interrupted run resumes and
the table can be printed again without running anything (--print-only).

One findmug-eval takes 6-45 s on the 2-core VM; the 29 rows x 3 seeds about 20 min, with 12
paired seeds about 80 min. The rows are the issue 35 levers: each alone on top of the
configuration before issue 35, the shipped one without each of its parts, the shipped one with
each lever that did not ship, and raw-like copies of the frames (--degrade).
"""
import argparse
import concurrent.futures
import json
import os
import statistics
import subprocess
import sys

# The shipped settings (daemon/findmugd.yaml; models/findmug.fmf is trained with them).
SHIPPED = ["learner.classes=nyu13", "features.objects=true", "features.objects_columns=relations",
           "forest.num_trees=16", "forest.shrinkage=20", "mrf.object_consistency=0.5",
           "mrf.pairwise=context", "cloud.fill_depth_max_run_px=40"]
# The configuration before issue 35 (shipped until ee27075): the common flags alone, with the
# label image's holes left empty as they were then.
BEFORE = ["labels.fill_holes=false"]
XGBOOST = ["learner.kind=xgboost", "xgboost.rounds=100", "xgboost.max_depth=4", "xgboost.eta=0.2",
           "xgboost.subsample=0.8", "xgboost.colsample=0.8"]
PSEUDO = ["training.pseudo_rounds=1", "training.pseudo_min_confidence=0.8"]


def without(settings, key, value=None):
    """`settings` with `key` replaced by key=value (dropped when value is None)."""
    kept = [s for s in settings if s.split("=")[0] != key]
    return kept + ([f"{key}={value}"] if value is not None else [])


# (name, table label, settings, extra flags, reference row for the paired column or None)
ROWS = [
    ("before", "**before** (the configuration shipped before: regions + scene features, 8 labels, 8 trees, no hole fill)",
     BEFORE, [], None),
    ("before+nyu13", "+ NYU-13 internal classes (`learner.classes=nyu13`)",
     BEFORE + ["learner.classes=nyu13"], [], "before"),
    ("before+nyu40", "+ NYU-40 internal classes (`learner.classes=nyu40`)",
     BEFORE + ["learner.classes=nyu40"], [], "before"),
    ("before+objects", "+ object features (`features.objects=true`, `objects_columns=context`)",
     BEFORE + ["features.objects=true"], [], "before"),
    ("before+ctxpair", "+ learned context pairwise term (`mrf.pairwise=context`)",
     BEFORE + ["mrf.pairwise=context"], [], "before"),
    ("before+layout", "+ label-layout prior of 594 NYU label maps (`mrf.pairwise=layout`, weight 5)",
     BEFORE + ["mrf.pairwise=layout", "mrf.layout_weight=5"], [], "before"),
    ("before+xgb", "+ gradient-boosted trees instead of the forest (`learner.kind=xgboost`)",
     BEFORE + XGBOOST, [], "before"),
    ("before+pseudo", "+ a semi-supervised round on the 10 unlabelled frames (`--unlabelled`)",
     BEFORE + PSEUDO, ["--unlabelled", "{data}/nyuv2_unlabeled_train"], "before"),
    ("before+rawcopies", "+ a raw-like training copy of every frame (`training.degraded_copies=1`)",
     BEFORE + ["training.degraded_copies=1"], [], "before"),
    ("before+labelholes", "+ the label image's depth holes filled (`labels.fill_holes`)",
     without(BEFORE, "labels.fill_holes"), [], "before"),
    ("shipped", "**shipped** (`daemon/findmugd.yaml`, `models/findmug.fmf`)", SHIPPED, [], "before"),
    ("shipped-softtop", "shipped without the table-top test (`tables.min_flat_share=0`)",
     SHIPPED + ["tables.min_flat_share=0"], [], "shipped"),
    ("shipped-nyu13", "shipped with the 8 labels instead of NYU-13 classes",
     without(SHIPPED, "learner.classes", "labels"), [], "shipped"),
    ("shipped-objects", "shipped without object features (object consistency then has no candidates)",
     without(SHIPPED, "features.objects", "false"), [], "shipped"),
    ("shipped-relations", "shipped without the load-on-top column (`objects_columns=context`)",
     without(SHIPPED, "features.objects_columns", "context"), [], "shipped"),
    ("shipped-16trees", "shipped with 8 trees instead of 16",
     without(SHIPPED, "forest.num_trees", "8"), [], "shipped"),
    ("shipped-shrinkage", "shipped without leaf shrinkage (`forest.shrinkage=0`)",
     without(SHIPPED, "forest.shrinkage", "0"), [], "shipped"),
    ("shipped-objcons", "shipped without object consistency (`mrf.object_consistency=0`)",
     without(SHIPPED, "mrf.object_consistency", "0"), [], "shipped"),
    ("shipped-depthfill", "shipped without the depth fill (`cloud.fill_depth_max_run_px=0`)",
     without(SHIPPED, "cloud.fill_depth_max_run_px", "0"), [], "shipped"),
    ("shipped-labelholes", "shipped without the label-hole fill (`labels.fill_holes=false`)",
     SHIPPED + ["labels.fill_holes=false"], [], "shipped"),
    ("shipped-ctxpair", "shipped with the paper's Potts term instead of the learned one (`mrf.pairwise=potts`)",
     without(SHIPPED, "mrf.pairwise", "potts"), [], "shipped"),
    ("shipped+nyu40", "shipped with NYU-40 classes instead of NYU-13",
     without(SHIPPED, "learner.classes", "nyu40"), [], "shipped"),
    ("shipped+xgb", "shipped with gradient-boosted trees instead of the forest",
     SHIPPED + XGBOOST, [], "shipped"),
    ("shipped+pseudo", "shipped + a semi-supervised round",
     SHIPPED + PSEUDO, ["--unlabelled", "{data}/nyuv2_unlabeled_train"], "shipped"),
    ("shipped+rawcopies", "shipped + a raw-like training copy of every frame",
     SHIPPED + ["training.degraded_copies=1"], [], "shipped"),
    ("before@raw", "*raw-like copies (`--degrade`)*: before", BEFORE, ["--degrade"], None),
    ("shipped@raw", "*raw-like copies*: **shipped**", SHIPPED, ["--degrade"], "before@raw"),
    ("shipped-depthfill@raw", "*raw-like copies*: shipped without the depth fill",
     without(SHIPPED, "cloud.fill_depth_max_run_px", "0"), ["--degrade"], "shipped@raw"),
    ("shipped-ctxpair@raw", "*raw-like copies*: shipped with the Potts term",
     without(SHIPPED, "mrf.pairwise", "potts"), ["--degrade"], "shipped@raw"),
    ("shipped-labelholes@raw", "*raw-like copies*: shipped without the label-hole fill",
     SHIPPED + ["labels.fill_holes=false"], ["--degrade"], "shipped@raw"),
    ("shipped-softtop@raw", "*raw-like copies*: shipped without the table-top test",
     SHIPPED + ["tables.min_flat_share=0"], ["--degrade"], "shipped@raw"),
    ("shipped+nyu40@raw", "*raw-like copies*: shipped with NYU-40 classes",
     without(SHIPPED, "learner.classes", "nyu40"), ["--degrade"], "shipped@raw"),
]


def eval_command(args, settings, extra, seed, json_path):
    d = args.data
    cmd = [os.path.join(args.build_dir, "tools", "findmug-eval"),
           "--data", f"{d}/nyuv2_labeled", "--data", f"{d}/nyuv2_labeled_extra", "--folds", "5",
           "--nyu-split", f"{d}/nyuv2_meta/split_test_indices.txt",
           "--nyu-rotations", f"{d}/nyuv2_meta/camera_rotations_NYU.txt",
           "--json", json_path]
    common = ["ground.source=gravity", "features.regions=true", "features.scene=true",
              "learner.num_threads=1", f"forest.seed={seed}"]
    if any(s.startswith("learner.kind=xgboost") for s in settings):
        common.append(f"xgboost.seed={seed}")
    for s in common + settings:
        cmd += ["--set", s]
    return cmd + [e.format(data=d) for e in extra]


def figures(path):
    """The row's figures from one findmug-eval JSON report, in percent."""
    with open(path) as f:
        report = json.load(f)
    mrf, searchable, instances = report["mrf"], report["searchable_tables"], report["table_instances"]
    per_class = mrf["per_class"]
    return {"class_avg": 100 * mrf["class_average"], "global": 100 * mrf["global"],
            "table": 100 * per_class["table"], "chair": 100 * per_class["chair"],
            "cabinet": 100 * per_class["cabinet"],
            "inst_p": 100 * instances["precision"], "inst_r": 100 * instances["recall"],
            "search_p": 100 * searchable["precision"], "search_r": 100 * searchable["recall"],
            "false_frames": 100 * searchable["false_table_frame_share"]}


def run_one(args, name, settings, extra, seed, path):
    cmd = eval_command(args, settings, extra, seed, path + ".part")
    print(f"{name} seed {seed}", file=sys.stderr, flush=True)
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        return (f"accuracy_table: {name} seed {seed} failed ({' '.join(cmd)}):\n"
                f"{done.stderr[-2000:]}")
    os.replace(path + ".part", path)
    return None


def run_rows(args, rows, seeds):
    """Every row x seed whose JSON is missing, seed by seed (the table's seeds finish first),
    --jobs at a time (each findmug-eval runs on one thread)."""
    work = [(name, settings, extra, seed, os.path.join(args.out, f"{name}-{seed}.json"))
            for seed in seeds for name, _, settings, extra, _ in rows]
    work = [w for w in work if not os.path.exists(w[4])]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for error in pool.map(lambda w: run_one(args, *w), work):
            if error:
                sys.exit(error)


def row_figures(args, name, seeds):
    paths = [os.path.join(args.out, f"{name}-{s}.json") for s in seeds]
    return [figures(p) for p in paths] if all(os.path.exists(p) for p in paths) else None


def table(args, rows, seeds, paired_seeds):
    mean = statistics.mean
    out = ["| forest + MRF, % | class avg | global | table | chair | cabinet | table instances P / R "
           f"| searchable tables P / R | frames with a false table | {len(paired_seeds)} seeds: "
           "class avg, against the row named (seeds higher) |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for name, label, _, _, reference in rows:
        r = row_figures(args, name, seeds)
        if r is None:
            out.append(f"| {label} | (not run) |||||||||")
            continue

        def cell(key):
            values = [x[key] for x in r]
            return f"{mean(values):.1f} ({' / '.join(f'{v:.1f}' for v in values)})"

        cells = [cell(k) for k in ("class_avg", "global", "table", "chair", "cabinet")]
        cells.append(f"{mean(x['inst_p'] for x in r):.1f} / {mean(x['inst_r'] for x in r):.1f}")
        cells.append(f"{mean(x['search_p'] for x in r):.1f} / {mean(x['search_r'] for x in r):.1f}")
        cells.append(f"{mean(x['false_frames'] for x in r):.1f}")
        paired = row_figures(args, name, paired_seeds) if len(paired_seeds) > len(seeds) else None
        against = row_figures(args, reference, paired_seeds) if paired and reference else None
        if paired and against:
            diffs = [a["class_avg"] - b["class_avg"] for a, b in zip(paired, against)]
            higher = sum(d > 1e-9 for d in diffs)
            cells.append(f"{mean(x['class_avg'] for x in paired):.1f}, {mean(diffs):+.1f} against "
                         f"{reference.split('@')[0]} ({higher} of {len(diffs)})")
        elif paired:
            cells.append(f"{mean(x['class_avg'] for x in paired):.1f}")
        else:
            cells.append("")
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def nyu40_table(args, rows, seeds):
    """What becomes "table" (`table_by_nyu40` in the JSON), the rows side by side: per true
    NYU-40 class, summed over the seeds, its share of the pixels labelled table and the
    share of the class labelled table; the classes that are most of the table pixels in any
    row, then bed, sofa and counter."""
    sums = {}
    for name, *_ in rows:
        pixels, table = {}, {}
        for seed in seeds:
            path = os.path.join(args.out, f"{name}-{seed}.json")
            if not os.path.exists(path):
                return f"(row {name} seed {seed} not run)"
            with open(path) as f:
                report = json.load(f)
            if "table_by_nyu40" not in report:
                return f"({path} has no table_by_nyu40: frames without label40/)"
            for c in report["table_by_nyu40"]["classes"]:
                pixels[c["class"]] = pixels.get(c["class"], 0) + c["pixels"]
                table[c["class"]] = table.get(c["class"], 0) + c["labelled_table"]
        sums[name] = (pixels, table)
    order = []
    for pixels, table in sums.values():
        order += sorted(table, key=lambda c: -table[c])[:10]
    order += ["bed", "sofa", "counter", "table", "desk"]
    order = list(dict.fromkeys(order))
    names = [r[0] for r in rows]
    out = ["| true NYU-40 class | " + " | ".join(
               f"{n}: share of the table pixels | {n}: share of the class labelled table"
               for n in names) + " |",
           "|---|" + "---:|---:|" * len(names)]
    totals = {n: sum(sums[n][1].values()) for n in names}
    for c in order:
        cells = []
        for n in names:
            pixels, table = sums[n]
            cells.append(f"{100 * table.get(c, 0) / max(1, totals[n]):.1f} %")
            cells.append(f"{100 * table.get(c, 0) / max(1, pixels.get(c, 0)):.1f} %")
        out.append(f"| {c} | " + " | ".join(cells) + " |")
    out.append("| all pixels labelled table | " + " | ".join(
        f"{totals[n]} | " for n in names) + "|")
    return "\n".join(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build-dir", default="build")
    p.add_argument("--data", default=os.environ.get("FINDMUG_DATA", "../shared/data"))
    p.add_argument("--out", default="accuracy-table")
    p.add_argument("--seeds", type=int, default=3, help="seeds in the table's cells")
    p.add_argument("--paired-seeds", type=int, default=12,
                   help="seeds for the paired column (0: no paired column)")
    p.add_argument("--rows", default="", help="comma-separated row names (default: all)")
    p.add_argument("--jobs", type=int, default=1,
                   help="findmug-eval runs at a time (each is single-threaded; default 1)")
    p.add_argument("--print-only", action="store_true", help="print the table from --out's JSON")
    p.add_argument("--nyu40", action="store_true",
                   help="also print what becomes table (true NYU-40 class), the rows side by side")
    args = p.parse_args()
    names = [n for n in args.rows.split(",") if n]
    known = {r[0] for r in ROWS}
    unknown = [n for n in names if n not in known]
    if unknown:
        sys.exit(f"accuracy_table: unknown row(s) {', '.join(unknown)} (rows: {', '.join(sorted(known))})")
    rows = [r for r in ROWS if not names or r[0] in names]
    seeds = [42 + 1000 * k for k in range(args.seeds)]
    paired_seeds = [42 + 1000 * k for k in range(max(args.paired_seeds, args.seeds))]
    os.makedirs(args.out, exist_ok=True)
    if not args.print_only:
        run_rows(args, rows, paired_seeds)
    print(table(args, rows, seeds, paired_seeds))
    if args.nyu40:
        print()
        print(nyu40_table(args, rows, seeds))


if __name__ == "__main__":
    main()
