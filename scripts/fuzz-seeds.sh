#!/usr/bin/env bash
# Regenerates the fuzz seed corpora under tests/fuzz/corpus/ with the project's
# own encoders and writers (findmug-fuzz-seeds), e.g. after a wire or model
# format change. Review the diff and commit it.
#
#   scripts/fuzz-seeds.sh            # build dir: build/
#   BUILD_DIR=/tmp/b scripts/fuzz-seeds.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
source scripts/build-env.sh
if [[ ! -f "$BUILD_DIR/CMakeCache.txt" ]]; then
  scripts/configure.sh "$BUILD_DIR"
fi
cmake --build "$BUILD_DIR" -j"${JOBS:-$(nproc)}" --target findmug-fuzz-seeds
seeds=$(find "$BUILD_DIR" -name findmug-fuzz-seeds -type f -perm -u+x | head -n1)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$seeds" . "$tmp"
rm -rf tests/fuzz/corpus
mkdir -p tests/fuzz
mv "$tmp" tests/fuzz/corpus
chmod 755 tests/fuzz/corpus
echo "tests/fuzz/corpus regenerated:"
find tests/fuzz/corpus -type f | sort
