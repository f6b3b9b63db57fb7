#!/usr/bin/env python3
"""The core's rooms: where each file of src/, include/findmug/ and tests/unit/ lives.

  rooms.py check     fail, naming each file, when a file under src/ROOM/, include/findmug/ROOM/
                     or tests/unit/ROOM/ is not listed in ROOMS (or ROOM is not a room);
                     run by ctest (`rooms`)

  rooms.py move      git-mv every flat core file into its room (skips what is moved) and
                     then rewrites references (below)
  rooms.py includes  rewrite old flat references in every tracked text file: #include
                     "findmug/X.hpp" -> "findmug/<room>/X.hpp", internal "X_internal.hpp"
                     -> "<room>/X_internal.hpp", and paths such as src/X.cpp in comments and
                     documents; then the references to renamed rooms and files (RENAMED).
                     Idempotent: run it after merging a branch that predates the move or a rename.
"""
import os
import re
import subprocess
import sys

# room -> (public headers in include/findmug/, sources and internal headers in src/, unit tests)
ROOMS = {
    "common": (["error", "numbers", "pose2d"],
               ["numbers.cpp", "pose2d.cpp", "cpu_features.hpp", "floor_to_int.hpp", "int_runs.hpp",
                "min_max2.hpp", "scratch.hpp", "simd_table.hpp", "simd_vec3.hpp",
                "union_find.hpp", "point_extent.hpp", "csv_rows.cpp", "csv_rows.hpp"],
               ["numbers", "csv_rows"]),
    "frame": (["frame", "image_io", "dataset", "depth_holes"],
              ["frame.cpp", "image_io.cpp", "dataset.cpp", "depth_holes.cpp"],
              ["image_io", "dataset", "depth_holes"]),
    "cloud": (["cloud"], ["cloud.cpp", "cloud_internal.hpp"], ["cloud"]),
    "ground": (["ground", "ground_tracker"],
               ["ground.cpp", "ground_gravity.cpp", "ground_internal.hpp", "ground_tracker.cpp"],
               ["ground"]),
    "oversegmentation": (["oversegmentation"],
                         ["oversegmentation.cpp", "oversegmentation_internal.hpp",
                          "oversegmentation_organized.cpp", "oversegmentation_pcl.cpp", "lab_internal.hpp",
                          "lab.cpp", "organized_internal.hpp", "organized_kernels.hpp",
                          "organized_seeds.cpp", "organized_connectivity.cpp"],
                         ["oversegmentation"]),
    "features": (["features", "region_features", "scene_features", "context_features", "object_features"],
                 ["features.cpp", "features_internal.hpp", "moments_internal.hpp", "region_features.cpp",
                  "scene_features.cpp", "context_features.cpp", "object_features.cpp"],
                 ["features", "region_features", "scene_features", "context_features", "object_features"]),
    "learner": (["forest"],
                ["forest.cpp", "forest_format.cpp", "forest_format.hpp",
                 "xgboost_learner.cpp", "xgboost_learner.hpp"],
                ["forest", "learner"]),
    "mrf": (["mrf", "context_pairwise", "object_consistency", "layout_prior"],
            ["mrf.cpp", "mrf_internal.hpp", "context_pairwise.cpp", "object_consistency.cpp",
             "layout_prior.cpp"], ["mrf", "object_consistency", "layout_prior"]),
    "labels": (["labels", "label_image", "label_holes"], ["label_image.cpp", "label_holes.cpp"],
               ["label_image", "label_holes"]),
    "segmenter": (["segmenter"], ["segmenter.cpp", "type_layout.cpp", "type_layout.hpp"],
                 ["segmenter", "type_layout", "buffer_reuse", "segmenter_context", "segmenter_layout",
                  "segmenter_objects", "segmenter_table_objects"]),
    "tables": (["tables", "table_regions"],
               ["tables.cpp", "tables_internal.hpp", "table_clustering.cpp", "table_geometry.cpp",
                "table_reachability.cpp", "table_regions.cpp", "table_search_positions.cpp",
                "table_top.cpp"],
               ["tables", "table_regions", "table_top"]),
    "objects": (["table_objects", "object_model", "object_matcher"],
                ["table_objects.cpp", "table_objects_clustering.cpp", "table_objects_internal.hpp",
                 "object_colour.cpp", "object_model.cpp", "object_matcher.cpp",
                 "shape_descriptor.cpp", "roundness.cpp"],
                ["table_objects", "object_model", "object_matcher"]),
    "map": (["table_map", "semantic_map", "object_map", "object_search", "visiting_order",
             "table_top_views", "depth_view"],
            ["table_map.cpp", "semantic_map.cpp", "semantic_map_settings.cpp",
             "semantic_map_tables.cpp", "semantic_map_file.cpp", "semantic_map_internal.hpp",
             "object_map.cpp", "object_search.cpp", "visiting_order.cpp", "table_top_views.cpp",
             "depth_view.cpp"],
            ["table_map", "semantic_map", "object_map", "object_search", "visiting_order",
             "table_top_views", "depth_view"]),
    "settings": (["config", "settings", "offline_settings"],
                 ["config.cpp", "settings.cpp", "segmenter_settings.cpp", "offline_settings.cpp",
                  "setting_builders_internal.hpp"],
                 ["config", "settings", "recorded_settings", "model_settings"]),
    "offline": (["training", "metrics", "table_metrics", "cv_folds", "depth_degradation", "mrf_context",
                 "nyu_mat", "layout_counts", "pseudo_labels"],
                ["training.cpp", "metrics.cpp", "table_metrics.cpp", "cv_folds.cpp",
                 "depth_degradation.cpp", "mrf_context.cpp", "nyu_mat.cpp", "layout_counts.cpp",
                 "pseudo_labels.cpp", "forest_train.cpp", "xgboost_train.cpp"],
                ["cv_folds", "depth_degradation", "mrf_context", "nyu_mat", "table_metrics",
                 "fine_label_inference", "layout_counts", "pseudo_labels"]),
    # synth builds in its own CMakeLists.txt and includes synth_internal.hpp from its own folder
    "synth": (["synth"], ["camera_path.cpp", "ground_truth.cpp", "render.cpp", "scene.cpp", "apartment.cpp",
                          "scene_edit.cpp", "synth_internal.hpp"], ["synth", "apartment"]),
}

# Rooms and files renamed after the move, old -> new: `includes` rewrites references to them
# (paths, #include lines) in a branch that predates the rename.
RENAMED = [
    ("supervoxels/overseg_organized.cpp", "oversegmentation/oversegmentation_organized.cpp"),
    ("supervoxels/overseg_pcl.cpp", "oversegmentation/oversegmentation_pcl.cpp"),
    ("supervoxels/", "oversegmentation/"),
    ("overseg_organized.cpp", "oversegmentation_organized.cpp"),
    ("overseg_pcl.cpp", "oversegmentation_pcl.cpp"),
    ("findmug/pipeline/", "findmug/segmenter/"),
    ("src/pipeline/", "src/segmenter/"),
    ("tests/unit/pipeline/", "tests/unit/segmenter/"),
    # The layout check names types of every room: it sits at the top, with the Segmenter.
    ("common/type_layout.", "segmenter/type_layout."),
    ("tests/unit/common/type_layout_test.cpp", "tests/unit/segmenter/type_layout_test.cpp"),
    ("common/moments_internal.hpp", "features/moments_internal.hpp"),
]

# Rooms built by their own CMakeLists.txt with their folder on the include path: their internal
# headers are included by bare name and are not rewritten to "ROOM/X.hpp".
OWN_INCLUDE_DIR = {"synth"}


def unlisted():
    """Files under a room's three folders that ROOMS does not list, and folders that are no room."""
    problems = []
    for base, kind in (("src", 1), ("include/findmug", 0), ("tests/unit", 2)):
        if not os.path.isdir(base):
            continue
        for room in sorted(os.listdir(base)):
            folder = os.path.join(base, room)
            if not os.path.isdir(folder):
                continue
            if room not in ROOMS:
                problems.append(f"{folder}/: not a room in scripts/dev/rooms.py ROOMS")
                continue
            listed = ROOMS[room][kind]
            if kind == 0:
                names = {f"{h}.hpp" for h in listed}
            elif kind == 2:
                names = {f"{t}_test.cpp" for t in listed}
            else:
                names = set(listed) | {"CMakeLists.txt"}
            for dirpath, _, files in os.walk(folder):
                for f in sorted(files):
                    rel = os.path.relpath(os.path.join(dirpath, f), folder)
                    if rel not in names:
                        problems.append(f"{os.path.join(folder, rel)}: not listed in room '{room}'")
    return problems


def check():
    problems = unlisted()
    for p in problems:
        print(f"rooms.py: {p}")
    if problems:
        sys.exit(f"rooms.py check: {len(problems)} file(s) not listed; add them to ROOMS")
    print(f"rooms.py check: every file of src/, include/findmug/ and tests/unit/ rooms is listed "
          f"({len(ROOMS)} rooms)")


def top():
    return subprocess.check_output(["git", "rev-parse", "--show-toplevel"], text=True,
                                   cwd=os.path.dirname(os.path.abspath(__file__))).strip()


def git_mv(src, dst):
    if os.path.exists(src) and not os.path.exists(dst):
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        subprocess.check_call(["git", "mv", src, dst])


def move():
    for room, (headers, sources, tests) in ROOMS.items():
        for h in headers:
            git_mv(f"include/findmug/{h}.hpp", f"include/findmug/{room}/{h}.hpp")
        for s in sources:
            git_mv(f"src/{s}", f"src/{room}/{s}")
        for t in tests:
            git_mv(f"tests/unit/{t}_test.cpp", f"tests/unit/{room}/{t}_test.cpp")
    left = [f for f in os.listdir("src") if os.path.isfile(os.path.join("src", f)) and f != "CMakeLists.txt"]
    left += [f for f in os.listdir("include/findmug") if os.path.isfile(os.path.join("include/findmug", f))
             and f != "version.hpp.in"]
    left += [f for f in os.listdir("tests/unit") if f.endswith("_test.cpp")]
    if left:
        sys.exit("rooms.py: no room for " + ", ".join(sorted(left)) + " (add them to ROOMS)")


def replacements():
    """(compiled pattern, replacement) pairs, each matching only the old flat spelling."""
    pairs = []
    for room, (headers, sources, tests) in ROOMS.items():
        for h in headers:
            pairs.append((re.compile(r'(?<![\w/])findmug/' + re.escape(h) + r'\.hpp\b'),
                          f"findmug/{room}/{h}.hpp"))
        for s in sources:
            # include/findmug/x.hpp and src/x.cpp spelled as paths in text and CMake
            pairs.append((re.compile(r'(?<![\w/])src/' + re.escape(s) + r'(?![\w])'), f"src/{room}/{s}"))
            if s.endswith(".hpp") and room not in OWN_INCLUDE_DIR:
                pairs.append((re.compile(r'#include "' + re.escape(s) + '"'), f'#include "{room}/{s}"'))
        for t in tests:
            pairs.append((re.compile(r'(?<![\w/])tests/unit/' + re.escape(t) + r'_test\.cpp\b'),
                          f"tests/unit/{room}/{t}_test.cpp"))
    pairs.append((re.compile(r'(?<![\w/])include/findmug/([a-z_0-9]+)\.hpp\b'), None))
    for old, new in RENAMED:
        # findmug/OLD, src/OLD, tests/unit/OLD, "OLD (an internal #include) and OLD at a word start
        pairs.append((re.compile(r'(?<![\w.-])' + re.escape(old)), new))
    return pairs


def header_room():
    return {h: room for room, (headers, _, _) in ROOMS.items() for h in headers}


def rewrite_text(text, pairs, rooms_of):
    for pattern, repl in pairs:
        if repl is None:
            text = pattern.sub(lambda m: (f"include/findmug/{rooms_of[m.group(1)]}/{m.group(1)}.hpp"
                                          if m.group(1) in rooms_of else m.group(0)), text)
        else:
            text = pattern.sub(repl, text)
    return text


def includes():
    pairs = replacements()
    rooms_of = header_room()
    files = subprocess.check_output(["git", "ls-files"], text=True).split("\n")
    files += subprocess.check_output(["git", "ls-files", "--others", "--exclude-standard"], text=True).split("\n")
    changed = 0
    for f in files:
        if not f or not os.path.isfile(f) or f.startswith(("models/", "tests/fixtures/")):
            continue
        if f == "scripts/dev/rooms.py" or f.endswith((".png", ".jpg", ".fmf", ".gz", ".lcmlog", ".bin", ".oni")):
            continue
        try:
            text = open(f, encoding="utf-8").read()
        except (UnicodeDecodeError, IsADirectoryError):
            continue
        new = rewrite_text(text, pairs, rooms_of)
        if new != text:
            open(f, "w", encoding="utf-8").write(new)
            changed += 1
    print(f"rooms.py: rewrote references in {changed} files")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "check":
        os.chdir(sys.argv[2])
    else:
        os.chdir(top())
    if len(sys.argv) < 2 or sys.argv[1] not in ("move", "includes", "check"):
        sys.exit(__doc__)
    if sys.argv[1] == "check":
        check()
        sys.exit(0)
    if sys.argv[1] == "move":
        move()
    includes()
