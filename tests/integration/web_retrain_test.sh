#!/usr/bin/env bash
# web_retrain_test.sh — findmug-web's Retrain page in headless chromium, with a running
# findmugd: cross-validate on a small folder of real NYU frames (a tiny forest, set on the
# page), cancel a training, train, Install, and see findmugd run the new model
# (clients/web/test/retrain_test.mjs).
#
#   web_retrain_test.sh --findmugd B --web B --train B --eval B [--out DIR]
#
# In a private network namespace (loopback only, udpm multicast routed on it): findmugd
# replays the folder at 2 frames/s with a model trained here first, and listens for
# commands on the udpm bus findmug-web publishes on; findmug-web serves 127.0.0.1 and
# runs findmug-train / findmug-eval with the same config file. Exit 0 pass, 1 fail, 77
# skipped (chromium, node, puppeteer-core or data missing; failures under CI=true).
set -euo pipefail
FINDMUGD="" WEB="" TRAIN="" EVAL="" OUT=""
SOURCE_DIR="$(cd "$(dirname "$0")/../.." && pwd)"
ARGS=("$@")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --findmugd) FINDMUGD=$2; shift 2 ;;
    --web) WEB=$2; shift 2 ;;
    --train) TRAIN=$2; shift 2 ;;
    --eval) EVAL=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "web_retrain_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
for b in "$FINDMUGD" "$WEB" "$TRAIN" "$EVAL"; do
  [[ -x "$b" ]] || { echo "web_retrain_test: --findmugd, --web, --train and --eval must name executables" >&2; exit 2; }
done
SKIP_NAME="web_retrain_test"
source "$SOURCE_DIR/tests/support/skip.sh"
source "$SOURCE_DIR/tests/support/web_test.sh"
web_test_needs_browser
NYU="${FINDMUG_DATA:-$SOURCE_DIR/../shared/data}/nyuv2_labeled"
[[ -f "$NYU/rgb/0001.png" ]] || skip "NYU frames missing at $NYU (set FINDMUG_DATA)"
web_test_enter_netns "${ARGS[@]}"
URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
PORT=18092

web_test_workdir findmug-web-retrain

# A small folder: six labelled NYU frames whose floor the fast settings find (symlinks),
# split into two scenes for findmug-eval's 2 folds.
mkdir -p "$WORK/small/rgb" "$WORK/small/depth" "$WORK/small/label8" "$WORK/small/label13"
printf 'frame,scene\n' > "$WORK/small/frames.csv"
for n in 0009 0015 0016 0017 0018 0021; do
  for sub in rgb depth label8 label13; do ln -s "$NYU/$sub/$n.png" "$WORK/small/$sub/$n.png"; done
  printf '%s,%s\n' "$n" "$([[ $n < 0017 ]] && echo a || echo b)" >> "$WORK/small/frames.csv"
done
# The user's folder: one frame outside the small folder, rgb/ and depth/ copied (no labels;
# findmug-web refuses symlinks out of a data folder). NYU's label8 guides the greedy user only.
# findmug-web (the prediction, and the tools it runs) takes the frames' gravity from NYU's
# rotations: the fast settings find no floor in this frame's depth alone.
USER_FRAME=0014
mkdir -p "$WORK/user/rgb" "$WORK/user/depth"
for sub in rgb depth; do cp "$NYU/$sub/$USER_FRAME.png" "$WORK/user/$sub/"; done
# One config for findmugd, findmug-web and the tools it runs: the shipped model's kind
# (NYU-13 internal classes, object features) with the fast oversegmenter. The page writes
# label8/ only: the trainer must infer the user frame's NYU-13 classes from the small folder's.
printf 'oversegmentation:\n  method: organized\nlearner:\n  classes: nyu13\nfeatures:\n  objects: true\n  objects_columns: context\n' \
  > "$WORK/findmug.yaml"
TINY=(--set forest.num_trees=3 --set forest.max_depth=6)
"$TRAIN" --data "$WORK/small" --out "$WORK/installed.fmf" --config "$WORK/findmug.yaml" \
  "${TINY[@]}" > "$WORK/first-train.log" 2>&1 || fail "the first model could not be trained"
cp "$WORK/installed.fmf" "$WORK/first.fmf"  # the Label page's prediction
first_id=$(sed -n 's/.*(id \([0-9a-f]\{8\}\)).*/\1/p' "$WORK/first-train.log")
[[ -n "$first_id" ]] || fail "no model id in findmug-train's output"

"$FINDMUGD" --config "$WORK/findmug.yaml" --source "dataset:$WORK/small?rate_hz=2&loop=1" \
  --lcm-url "$URL" --model "$WORK/installed.fmf" --set daemon.status_period_s=0.5 \
  > "$WORK/findmugd.log" 2>&1 &
pids+=($!)
"$WEB" --lcm-url "$URL" --port "$PORT" --static-dir "$SOURCE_DIR/clients/web/static" \
  --config "$WORK/findmug.yaml" --set "web.jobs_dir=$WORK/jobs" \
  --set "web.install_path=$WORK/installed.fmf" --set "web.train_program=$TRAIN" \
  --set "web.eval_program=$EVAL" --set web.retrain_folds=2 --model "$WORK/first.fmf" \
  --nyu-rotations "$NYU/../nyuv2_meta/camera_rotations_NYU.txt" --set ground.source=gravity \
  --data "$WORK/small" --data "$WORK/user" > "$WORK/findmug-web.log" 2>&1 &
web_pid=$!
pids+=($web_pid)
web_test_wait_for_port "$PORT" "$web_pid"
node "$SOURCE_DIR/clients/web/test/retrain_test.mjs" --url "http://127.0.0.1:$PORT/" \
  --out "$OUT" --user-dir "$WORK/user" --user-frame "$USER_FRAME" --truth "$NYU/label8" \
  > "$WORK/page.log" || fail "the page check failed: $(cat "$WORK/page.log")"
cat "$WORK/page.log"
grep -q "model reload (command request" "$WORK/findmugd.log" || fail "findmugd logged no reload"
new_id=$(sed -n 's/^trained model id //p' "$WORK/page.log")
[[ -n "$new_id" && "$new_id" != "$first_id" ]] || fail "the installed model's id '$new_id' is not new (first $first_id)"
# The installed file is that model: findmug-eval loads it (a valid model file, same settings).
"$EVAL" --data "$WORK/small" --model "$WORK/installed.fmf" --config "$WORK/findmug.yaml" \
  > "$WORK/eval-installed.log" 2>&1 || fail "findmug-eval cannot use the installed model"
grep -q "$new_id" "$WORK/eval-installed.log" || fail "findmug-eval does not name model $new_id"
cmp -s "$WORK/installed.fmf" "$WORK/first.fmf" && fail "installed.fmf is still the first model"
echo "web_retrain_test: passed"
