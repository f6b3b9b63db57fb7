#!/bin/sh
# systemd-analyze verify on a configured unit (findmugd.service, findmug-web.service),
# with ExecStart pointing at the freshly built binary (the installed path need not exist yet).
# usage: daemon_unit_verify.sh SYSTEMD_ANALYZE UNIT_FILE BINARY
set -eu
analyze=$1 unit=$2 binary=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
name=$(basename "$unit")
sed "s|^ExecStart=[^ ]*|ExecStart=$binary|" "$unit" > "$dir/$name"
grep -q "^ExecStart=$binary " "$dir/$name"
# verify prints problems and exits non-zero on errors; warnings are errors here too.
out=$("$analyze" verify "$dir/$name" 2>&1) || { echo "$out"; exit 1; }
if [ -n "$out" ]; then echo "$out"; exit 1; fi
echo "systemd-analyze verify: $name OK"
