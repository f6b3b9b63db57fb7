#!/bin/sh
# systemd-analyze verify on the configured findmugd.service, with ExecStart
# pointing at the freshly built binary (the installed path need not exist yet).
# usage: daemon_unit_verify.sh SYSTEMD_ANALYZE UNIT_FILE FINDMUGD_BINARY
set -eu
analyze=$1 unit=$2 binary=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed "s|^ExecStart=[^ ]*|ExecStart=$binary|" "$unit" > "$dir/findmugd.service"
grep -q "^ExecStart=$binary " "$dir/findmugd.service"
# verify prints problems and exits non-zero on errors; warnings are errors here too.
out=$("$analyze" verify "$dir/findmugd.service" 2>&1) || { echo "$out"; exit 1; }
if [ -n "$out" ]; then echo "$out"; exit 1; fi
echo "systemd-analyze verify: findmugd.service OK"
