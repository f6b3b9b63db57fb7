#!/usr/bin/env bash
# Runs inside the throwaway root of package_install_test.sh (chroot, as root).
set -euo pipefail
cd /tmp/in
fail() { echo "package test (inside): FAIL: $*" >&2; exit 1; }

echo "== dpkg -i"
dpkg -i ./findmug_*.deb ./findmug-dev_*.deb

getent passwd findmug >/dev/null || fail "postinst did not create the system user findmug"
for group in video plugdev; do
  if getent group "$group" >/dev/null; then
    id -nG findmug | grep -qw "$group" || fail "findmug is not in group $group"
  fi
done
[[ -f /lib/systemd/system/findmugd.service ]] || fail "unit not installed"
if find /etc/systemd/system -name 'findmugd.service' | grep -q .; then
  fail "the unit was enabled by the package; the administrator should decide"
fi
dpkg-query -W -f='${Conffiles}\n' findmug | grep -q '/etc/findmug/findmugd.yaml' ||
  fail "/etc/findmug/findmugd.yaml is not a conffile"
grep -q '^User=findmug' /lib/systemd/system/findmugd.service || fail "unit does not run as findmug"
[[ -f /lib/systemd/system/findmug-web.service ]] || fail "findmug-web unit not installed"
if find /etc/systemd/system -name 'findmug-web.service' | grep -q .; then
  fail "findmug-web.service was enabled by the package"
fi
[[ "$(stat -c '%U:%G %a' /etc/findmug/web-token)" == "root:root 600" ]] ||
  fail "web token is not a root-only file: $(stat -c '%U:%G %a' /etc/findmug/web-token)"
[[ $(head -n 1 /etc/findmug/web-token | tr -d '\n' | wc -c) -eq 64 ]] || fail "web token is not 64 hex digits"
dpkg-query -W -f='${Conffiles}\n' findmug | grep -q '/etc/findmug/findmug-web.yaml' ||
  fail "/etc/findmug/findmug-web.yaml is not a conffile"
[[ -f /usr/share/findmug/web/index.html && -f /usr/share/findmug/web/live.js ]] ||
  fail "findmug-web's page is not installed"
[[ "$(findmug-web --version)" == "findmug-web $VERSION" ]] || fail "findmug-web --version"
[[ -f /usr/share/java/findmug_lcmtypes.jar ]] || fail "LCM types jar missing"
[[ -f /lib/sysctl.d/60-findmug-lcm.conf ]] || fail "sysctl snippet missing"

echo "== the core library the loader picks"
# LD_DEBUG=libs names each library as its constructors run ("calling init: PATH").
core_loaded() { env "$@" LD_DEBUG=libs findmugd --version 2>&1 >/dev/null |
  sed -n 's/.*calling init: \(.*libfindmug_core[^ ]*\).*/\1/p' | head -n 1; }
plain=$(core_loaded GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2)
echo "without AVX2 (GLIBC_TUNABLES): $plain"
[[ -n "$plain" && "$plain" != *glibc-hwcaps* ]] || fail "the plain core was not loaded ($plain)"
if [[ "${HWCAPS_COPY:-0}" == 1 ]]; then
  dpkg -L findmug | grep -q '/glibc-hwcaps/x86-64-v3/libfindmug_core.so.0.1$' ||
    fail "the x86-64-v3 copy of the core is not in the package"
  if /lib64/ld-linux-x86-64.so.2 --help | grep -q 'x86-64-v3 (supported'; then
    chosen=$(core_loaded)
    echo "as the loader chooses: $chosen"
    [[ "$chosen" == */glibc-hwcaps/x86-64-v3/libfindmug_core.so* ]] ||
      fail "the loader did not pick the installed x86-64-v3 copy ($chosen)"
  fi
fi

echo "== findmugd --version"
out=$(findmugd --version)
echo "$out"
[[ "$out" == "findmugd $VERSION" ]] || fail "findmugd --version printed '$out'"

echo "== findmugd --check-config (installed /etc/findmug/findmugd.yaml)"
findmugd --check-config >/tmp/check-config.txt
grep -q 'source: openni2' /tmp/check-config.txt || fail "--check-config did not show the installed config"

echo "== findmugd over a synthetic dataset, installed model"
findmug-synth --seed 3 --frames 3 --fps 5 --out /tmp/synth >/tmp/synth.log 2>&1 ||
  { cat /tmp/synth.log; fail "findmug-synth"; }
findmugd --source "dataset:/tmp/synth" --lcm-url "file:///tmp/out.lcmlog?mode=w" \
  >/tmp/daemon.log 2>&1 || { tail -n 30 /tmp/daemon.log; fail "findmugd over the dataset"; }
findmug-nav-client --lcm-url "file:///tmp/out.lcmlog?mode=r&speed=0" --json >/tmp/tables.json ||
  fail "findmug-nav-client"
frames=$(grep -c '"tour"' /tmp/tables.json || true)
echo "tables messages: $frames"
[[ "$frames" -eq 3 ]] || { head -c 2000 /tmp/tables.json; fail "expected 3 tables messages"; }

echo "== a CMake project against findmug-dev"
cmake -S /tmp/in/consumer -B /tmp/consumer-build -DCMAKE_BUILD_TYPE=Release >/tmp/consumer.log 2>&1 &&
  cmake --build /tmp/consumer-build >>/tmp/consumer.log 2>&1 || { cat /tmp/consumer.log; fail "consumer build"; }
out=$(/tmp/consumer-build/consumer)
echo "$out"
[[ "$out" == "findmug $VERSION nyu40_7=table tables_t bytes="* ]] || fail "consumer printed '$out'"

echo "== dpkg --purge"
dpkg --purge findmug-dev findmug
getent passwd findmug >/dev/null && fail "purge left the system user"
[[ -e /etc/findmug ]] && fail "purge left /etc/findmug"
echo "inside: all checks passed"
