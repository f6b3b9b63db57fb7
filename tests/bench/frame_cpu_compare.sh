#!/usr/bin/env bash
# frame_cpu_compare.sh — CPU per frame of two builds of the core, side by side.
#
#   tests/bench/frame_cpu_compare.sh BASE_BUILD [ROUNDS] [OUT.csv]
#
# Runs frame_cpu (one pass over the data after its warm-up pass, pinned to
# CPU 0, the shipped model and features) of BASE_BUILD and of ./build in
# turn, ROUNDS times (default 6), on the NYU frames and on a 60-frame
# synthetic apartment walk (findmug-synth --seed 7, rendered once into a
# temporary folder), and also ./build with tables.point_stride=2. On a
# virtual machine whose speed drifts from minute to minute, many short
# alternating runs and the median over them compare builds more fairly
# than one long run each. Prints the medians of the table stage and of the
# whole frame, and of their per-round ratios to the base build (with their
# range), and writes every run to OUT.csv (default frame_cpu_compare.csv).
# STAGE=NAME compares another row of frame_cpu's table instead of the table
# stage (e.g. STAGE=regions); VARIANTS="base new" leaves out the stride run.
# REPORTS=DIR keeps every frame_cpu report there and ends with the per-round
# ratio to the base build of every stage (several changes, one run).
set -euo pipefail
cd "$(dirname "$0")/../.."
base=${1:?usage: frame_cpu_compare.sh BASE_BUILD [ROUNDS] [OUT.csv]}
rounds=${2:-6}
out=${3:-frame_cpu_compare.csv}
stage=${STAGE:-tables}
read -r -a variants <<<"${VARIANTS:-base new new-stride2}"
[[ -x $base/tests/bench/frame_cpu ]] || { echo "no $base/tests/bench/frame_cpu" >&2; exit 1; }
[[ -x build/tests/bench/frame_cpu ]] || { echo "no build/tests/bench/frame_cpu" >&2; exit 1; }
export FINDMUG_DATA=${FINDMUG_DATA:-$PWD/../shared/data}
synth=$(mktemp -d)
trap 'rm -rf "$synth"' EXIT
build/tools/findmug-synth --seed 7 --frames 60 --out "$synth" >/dev/null

echo "data,variant,round,${stage}_ms,total_ms" >"$out"
for round in $(seq "$rounds"); do
  for data in synthetic nyu; do
    for variant in "${variants[@]}"; do
      exe=build/tests/bench/frame_cpu
      extra=()
      [[ $variant == base ]] && exe=$base/tests/bench/frame_cpu
      [[ $variant == new-stride2 ]] && extra=(--set tables.point_stride=2)
      [[ $data == synthetic ]] && extra+=(--data "$synth")
      report=$(taskset -c 0 "$exe" --model models/findmug.fmf --passes 1 \
        --set features.regions=true --set features.scene=true --set learner.classes=nyu13 \
        --set features.objects=true --set features.objects_columns=relations \
        --heap-keep-mb 256 "${extra[@]}")
      [[ -n ${REPORTS:-} ]] && mkdir -p "$REPORTS" && echo "$report" >"$REPORTS/$data-$variant-$round.md"
      tables=$(awk -F'|' -v s=" $stage " '$2 == s {print $3 + 0}' <<<"$report")
      total=$(awk -F'|' '$2 ~ /total/ {gsub(/\*/, "", $3); print $3 + 0}' <<<"$report")
      echo "$data,$variant,$round,$tables,$total" >>"$out"
    done
  done
done

# Medians of each stage, and of the per-round ratios to the base run (both
# ran seconds apart, so the host's drift cancels), with their range.
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2)}'; }
range() { sort -g | awk 'NR == 1 {lo = $1} {hi = $1} END {printf "%.2f-%.2f", lo, hi}'; }
echo "| data | variant | runs | $stage stage ms | whole frame ms | $stage / base per round | frame / base per round |"
echo "|---|---|---:|---:|---:|---|---|"
for data in nyu synthetic; do
  for variant in "${variants[@]}"; do
    rows=$(awk -F, -v d="$data" -v v="$variant" '$1 == d && $2 == v' "$out")
    ratios=$(awk -F, -v d="$data" -v v="$variant" '
      $1 == d && $2 == "base" {bt[$3] = $4; bf[$3] = $5}
      $1 == d && $2 == v {t[$3] = $4; f[$3] = $5}
      END {for (r in t) print t[r] / bt[r], f[r] / bf[r]}' "$out")
    printf "| %s | %s | %d | %.2f | %.2f | %.2f (%s) | %.2f (%s) |\n" "$data" "$variant" \
      "$(wc -l <<<"$rows")" "$(cut -d, -f4 <<<"$rows" | median)" "$(cut -d, -f5 <<<"$rows" | median)" \
      "$(cut -d' ' -f1 <<<"$ratios" | median)" "$(cut -d' ' -f1 <<<"$ratios" | range)" \
      "$(cut -d' ' -f2 <<<"$ratios" | median)" "$(cut -d' ' -f2 <<<"$ratios" | range)"
  done
done

# Every stage from the kept reports: median over rounds of variant / base.
if [[ -n ${REPORTS:-} ]]; then
  echo
  echo "| data | variant | stage | base ms (median) | variant ms (median) | variant / base per round |"
  echo "|---|---|---|---:|---:|---|"
  for data in nyu synthetic; do
    for variant in "${variants[@]}"; do
      [[ $variant == base ]] && continue
      stages=$(awk -F'|' 'NF > 4 && $3 ~ /[0-9]/ {gsub(/^ +| +$|\*/, "", $2); print $2}' \
        "$REPORTS/$data-base-1.md")
      while read -r name; do
        pairs=$(for round in $(seq "$rounds"); do
          b=$(awk -F'|' -v s="$name" '{n = $2; gsub(/^ +| +$|\*/, "", n)} n == s {gsub(/\*/, "", $3); print $3 + 0}' \
            "$REPORTS/$data-base-$round.md")
          v=$(awk -F'|' -v s="$name" '{n = $2; gsub(/^ +| +$|\*/, "", n)} n == s {gsub(/\*/, "", $3); print $3 + 0}' \
            "$REPORTS/$data-$variant-$round.md")
          echo "$b $v"
        done)
        printf "| %s | %s | %s | %.2f | %.2f | %.2f (%s) |\n" "$data" "$variant" "$name" \
          "$(cut -d' ' -f1 <<<"$pairs" | median)" "$(cut -d' ' -f2 <<<"$pairs" | median)" \
          "$(awk '$1 > 0 {print $2 / $1}' <<<"$pairs" | median)" \
          "$(awk '$1 > 0 {print $2 / $1}' <<<"$pairs" | range)"
      done <<<"$stages"
    done
  done
fi
