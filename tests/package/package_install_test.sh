#!/usr/bin/env bash
# package_install_test.sh BUILD_DIR SOURCE_DIR — the Debian packages, installed for real.
#
# 1. cpack -G DEB on the already-built tree (configured with CMAKE_INSTALL_PREFIX=/usr);
#    lintian must report no error (warnings are printed; README lists them).
# 2. A throwaway root: an overlay whose lower layer is this machine's / (read-only to the
#    test) and whose upper layer is a temporary folder, in a private mount namespace, and
#    chroot into it. dpkg, the maintainer scripts, adduser and the daemon run there
#    exactly as on a robot, and every file they write lands in the upper layer.
# 3. Inside: dpkg -i both packages; the system user exists, the unit is installed but not
#    enabled, the config is a conffile; findmugd --version, --check-config against the
#    installed config; findmugd over a short synthetic dataset (findmug-synth) with the
#    installed model, its tables read back by findmug-nav-client; a tiny CMake project
#    builds against findmug-dev (find_package(findmug)) and runs; dpkg --purge both.
# 4. Nothing left behind: after the purge the upper layer may hold only dpkg's own
#    bookkeeping and the test's scratch files; account files equal the originals.
# Needs root (mount namespace, overlayfs). Exit 77 = skipped (not under CI=true).
set -euo pipefail

build=$(cd "${1:?build dir}" && pwd)
source_dir=$(cd "${2:?source dir}" && pwd)

SKIP_NAME="package test"
source "$source_dir/tests/support/skip.sh"
need_root "mount namespace, overlayfs, chroot"
prefix=$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$build/CMakeCache.txt")
[[ "$prefix" == "/usr" ]] ||
  skip "build configured with CMAKE_INSTALL_PREFIX=$prefix; the package needs /usr (scripts/test.sh, scripts/package.sh)"
need_tools cpack lintian unshare chroot dpkg-deb

work=$(mktemp -d /tmp/findmug-package-test.XXXXXX)
cleanup() { rm -rf "$work"; }
trap cleanup EXIT

echo "== cpack"
(cd "$build" && cpack -G DEB -B "$work/cpack" -D CPACK_OUTPUT_FILE_PREFIX="$work/pkgs" \
   >"$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; exit 1; }
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$build/CMakeCache.txt")
arch=$(dpkg --print-architecture)
deb="$work/pkgs/findmug_${version}_${arch}.deb"
dev="$work/pkgs/findmug-dev_${version}_${arch}.deb"
for f in "$deb" "$dev"; do
  [[ -f "$f" ]] || { echo "package test: $f not made"; ls -l "$work/pkgs"; exit 1; }
done
ls -l "$work/pkgs"

echo "== lintian"
lintian --allow-root "$deb" "$dev" >"$work/lintian.txt" 2>&1 || true
grep -E '^[EW]: ' "$work/lintian.txt" || true
if grep -q '^E: ' "$work/lintian.txt"; then
  echo "package test: lintian reports errors"
  exit 1
fi

echo "== throwaway root"
mkdir -p "$work/upper" "$work/ovl-work" "$work/root" "$work/in"
cp "$deb" "$dev" "$work/in/"
cp -r "$source_dir/tests/package/consumer" "$work/in/consumer"
cp "$source_dir/tests/package/inside_root.sh" "$work/in/"
# The x86-64-v3 copy of the core (src/CMakeLists.txt, FINDMUG_CORE_HWCAPS): checked inside
# when this build made one.
hwcaps_copy=0
[[ -e "$build/src/glibc-hwcaps/x86-64-v3/libfindmug_core.so.0.1" ]] && hwcaps_copy=1
export work version hwcaps_copy
unshare --mount --pid --fork --propagation private bash -euo pipefail -c '
  mount -t overlay overlay -o "lowerdir=/,upperdir=$work/upper,workdir=$work/ovl-work" "$work/root"
  mount -t proc proc "$work/root/proc"
  mount --rbind /dev "$work/root/dev"
  mount -t tmpfs tmpfs "$work/root/tmp"
  mkdir -p "$work/root/tmp/in"
  mount --bind "$work/in" "$work/root/tmp/in"
  # No systemd runs in the throwaway root: maintainer scripts must cope, as in a chroot.
  mount -t tmpfs tmpfs "$work/root/run"
  chroot "$work/root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root \
    LANG=C.UTF-8 VERSION="$version" HWCAPS_COPY="$hwcaps_copy" bash /tmp/in/inside_root.sh
'

echo "== what the package left behind"
cd "$work/upper"
# dpkg bookkeeping, logs, caches and the test's own mount points are expected.
left=$(find . -mindepth 1 \( -path ./var/lib/dpkg -o -path ./var/log -o -path ./var/cache \
        -o -path ./tmp -o -path ./run -o -path ./proc -o -path ./dev -o -path ./root \) -prune -o -print |
       while read -r path; do
         rel=${path#./}
         if [[ -d "$path" && ! -L "$path" ]]; then
           # A directory the lower layer has too (copied up as a parent): fine if same.
           [[ -d "/$rel" ]] && continue
         fi
         case "$rel" in
           etc/passwd|etc/group|etc/shadow|etc/gshadow|etc/subuid|etc/subgid|etc/.pwd.lock)
             cmp -s "$path" "/$rel" && continue ;;  # rewritten by adduser/deluser, same again
           etc/passwd-|etc/group-|etc/shadow-|etc/gshadow-) continue ;;  # adduser backups
           etc/ld.so.cache)
             grep -q findmug "$path" || continue ;;
         esac
         echo "$rel"
       done)
if [[ -n "$left" ]]; then
  echo "package test: left behind after purge:"
  echo "$left"
  exit 1
fi
echo "package test: nothing left behind after purge"
echo "package test: PASS"
