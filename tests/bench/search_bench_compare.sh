#!/usr/bin/env bash
# search_bench_compare.sh — findmug-search-bench of two builds on the same episodes: the
# per-episode results must be the same bytes, and the CPU seconds each strategy costs an
# episode, side by side.
#
#   tests/bench/search_bench_compare.sh BASE_EXE [NEW_EXE] [OUT_DIR]
#
# NEW_EXE defaults to build/tools/search_bench/findmug-search-bench, OUT_DIR to a temporary
# folder (kept when given). Every strategy runs alone (--jobs 1, one process, its user + system
# CPU from /usr/bin/time), the base build and then the new one, under oracle perception on
# APARTMENTS apartments (default 3, one episode each), then under the matcher on
# MATCHER_APARTMENTS (default 1) with a budget of MATCHER_BUDGET simulated seconds (default
# 200: the baselines otherwise drive for 600 s under the matcher). STRATEGIES (default all
# five) and PERCEPTIONS (default "oracle matcher") narrow the runs. A speed-up that changes
# the search (a time, a path, a view, a find) shows as a differing episodes.csv: the script
# prints the first differing lines and exits 1.
#
# Prints one row per perception and strategy: episodes, base and new CPU s per episode and
# their ratio, and whether the episodes.csv files are identical. CPU time on a shared host
# varies with the load; the load average is printed before and after.
set -euo pipefail
cd "$(dirname "$0")/../.."
base=${1:?usage: search_bench_compare.sh BASE_EXE [NEW_EXE] [OUT_DIR]}
new=${2:-build/tools/search_bench/findmug-search-bench}
out=${3:-}
apartments=${APARTMENTS:-3}
matcher_apartments=${MATCHER_APARTMENTS:-1}
matcher_budget=${MATCHER_BUDGET:-200}
read -r -a strategies <<<"${STRATEGIES:-findmug places coverage random oracle}"
read -r -a perceptions <<<"${PERCEPTIONS:-oracle matcher}"
for exe in "$base" "$new"; do
  [[ -x $exe ]] || { echo "search_bench_compare: no executable $exe" >&2; exit 2; }
done
[[ -x /usr/bin/time ]] || { echo "search_bench_compare: needs /usr/bin/time" >&2; exit 2; }
if [[ -z $out ]]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
mkdir -p "$out"

cpu_of() {  # the "user system" line /usr/bin/time wrote, as seconds
  awk '{ print $1 + $2 }' "$1"
}

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-8s %-9s %8s %14s %14s %7s %s\n' perception strategy episodes "base CPU s/ep" \
  "new CPU s/ep" ratio "episodes.csv"
status=0
for perception in "${perceptions[@]}"; do
  n=$apartments
  extra=()
  if [[ $perception == matcher ]]; then
    n=$matcher_apartments
    extra=(--budget "$matcher_budget")
  fi
  for strategy in "${strategies[@]}"; do
    for side in base new; do
      exe=$base
      [[ $side == new ]] && exe=$new
      dir=$out/$perception-$strategy-$side
      /usr/bin/time -f '%U %S' -o "$dir.time" "$exe" --apartments "$n" \
        --episodes-per-apartment 1 --strategies "$strategy" --perception "$perception" \
        "${extra[@]}" --jobs 1 --quiet --out "$dir" >/dev/null
    done
    a=$(cpu_of "$out/$perception-$strategy-base.time")
    b=$(cpu_of "$out/$perception-$strategy-new.time")
    same=identical
    if ! cmp -s "$out/$perception-$strategy-base/episodes.csv" \
         "$out/$perception-$strategy-new/episodes.csv"; then
      same=DIFFERENT
      status=1
    fi
    awk -v p="$perception" -v s="$strategy" -v n="$n" -v a="$a" -v b="$b" -v same="$same" \
      'BEGIN { printf "%-8s %-9s %8d %14.3f %14.3f %7.3f %s\n", p, s, n, a / n, b / n,
               (a > 0 ? b / a : 0), same }'
    if [[ $same == DIFFERENT ]]; then
      diff "$out/$perception-$strategy-base/episodes.csv" \
        "$out/$perception-$strategy-new/episodes.csv" | head -6 >&2
    fi
  done
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
exit "$status"
