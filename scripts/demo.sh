#!/usr/bin/env bash
# The main job on bundled data: builds relief, turns the SRTM tiles of the
# eastern Pyrenees and Catalonia into a tile pyramid, verifies it and describes it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
BUILD_DIR=${RELIEF_BUILD_DIR:-build}
OUT=${1:-out/pyrenees}
"$BUILD_DIR/apps/relief/relief" build data/srtm/N41E001.hgt.zip data/srtm/N42E001.hgt.zip \
  -o "$OUT" --kind elevation --overwrite
"$BUILD_DIR/apps/relief/relief" verify "$OUT"
"$BUILD_DIR/apps/relief/relief" info "$OUT"
