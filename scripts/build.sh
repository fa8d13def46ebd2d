#!/usr/bin/env bash
# Configures and builds relief into build/ (or $RELIEF_BUILD_DIR). Extra
# arguments go to cmake's configure step, e.g. -DRELIEF_WERROR=ON to make
# warnings errors as the presets and CI do (docs/building.md).
# RELIEF_BUILD_TARGETS (space-separated) builds only those targets and what
# they need: scripts/demo.sh builds the relief program alone, not the tests.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${RELIEF_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=${CMAKE_BUILD_TYPE:-RelWithDebInfo} "$@" >/dev/null
targets=()
for t in ${RELIEF_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$BUILD_DIR" --parallel "$(nproc)" "${targets[@]}"
