#!/usr/bin/env bash
# ctest `shipped_has_no_training`: the code that trains a model (RandomForest::train, the
# forest's; RandomForest::trainBoosted, XGBoost's) lives in findmug_offline, which the shipped
# core library and findmugd do not contain; findmug-train does, which shows that the symbols
# are visible to this check at all.
#
#   no_training_in_shipped.sh CORE_LIBRARY FINDMUGD FINDMUG_TRAIN
set -euo pipefail
if [[ $# -ne 3 ]]; then
  echo "usage: no_training_in_shipped.sh CORE_LIBRARY FINDMUGD FINDMUG_TRAIN" >&2
  exit 2
fi
core=$1 daemon=$2 trainer=$3
for f in "$core" "$daemon" "$trainer"; do
  if [[ ! -f $f ]]; then
    echo "FAIL: $f is not built: build it first (nothing to check)" >&2
    exit 1
  fi
done
pattern='findmug::RandomForest::train(Boosted)?\('
# Functions a file defines (text symbols), demangled; the dynamic table of a shared library.
defined() { nm -C --defined-only "$@" 2>/dev/null | grep -E " [Tt] " || true; }
status=0
if defined -D "$core" | grep -E "$pattern"; then
  echo "FAIL: $core (the shipped core library) defines the training code above" >&2
  status=1
fi
if defined "$daemon" | grep -E "$pattern"; then
  echo "FAIL: $daemon defines the training code above" >&2
  status=1
fi
if ldd "$daemon" 2>/dev/null | grep -E "findmug_(offline|training)"; then
  echo "FAIL: $daemon loads a training library" >&2
  status=1
fi
if [[ $(defined "$trainer" | grep -cE "$pattern") -lt 2 ]]; then
  echo "FAIL: $trainer defines no RandomForest::train and trainBoosted: this check cannot see them" >&2
  status=1
fi
[[ $status -eq 0 ]] && echo "ok: neither $core nor $daemon holds the training code; $trainer does"
exit $status
