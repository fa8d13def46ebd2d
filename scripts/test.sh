#!/usr/bin/env bash
# Builds relief and runs the whole default test suite (the "slow" label is left
# out; run it with: ctest --test-dir build -L slow). Extra arguments go to
# scripts/build.sh's configure step (e.g. -DRELIEF_WERROR=ON).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh "$@"
BUILD_DIR=${RELIEF_BUILD_DIR:-build}
ctest --test-dir "$BUILD_DIR" --output-on-failure --parallel "$(nproc)" -LE slow
