#!/usr/bin/env bash
# The main job on bundled data: builds relief, turns the SRTM tiles of the
# eastern Pyrenees and Catalonia into a tile pyramid, verifies it, describes
# it, renders a still of it and flies over it (frames in out/pyrenees-flight/);
# builds a whole-Earth DEM and imagery pair, renders the planet and a movie
# descending from orbit; then builds the Umbra SAR image into a store, reduces its speckle and
# dynamic range on every level, and detects point targets.
set -euo pipefail
cd "$(dirname "$0")/.."
RELIEF_BUILD_TARGETS=relief scripts/build.sh   # the program alone, not the tests
BUILD_DIR=${RELIEF_BUILD_DIR:-build}
RELIEF="$BUILD_DIR/apps/relief/relief"
OUT=${1:-out/pyrenees}
"$RELIEF" build data/srtm/N41E001.hgt.zip data/srtm/N42E001.hgt.zip \
  -o "$OUT" --kind elevation --overwrite --fill-voids
"$RELIEF" verify "$OUT"
"$RELIEF" info "$OUT"
# A still of the pyramid, headless (EGL; Mesa's llvmpipe without a GPU).
"$RELIEF" render "$OUT" --look-at 1.5,42.5,1500,40000,0,-30 --size 1280x720 \
  -o "$OUT.png" --stats "$OUT-frame.json"
# A flight over it in interactive mode, through a simulated 20 ms, 50 Mbit/s
# link: frames never wait for data; coarse tiles show until detail arrives.
"$RELIEF" render "$OUT" --path data/paths/pyrenees-flyover.json -o "$OUT-flight" --size 640x360 \
  --simulate-latency 20 --simulate-bandwidth 50 --until-complete 10 --stats "$OUT-flight.json"

# A planet: ETOPO5 (the whole-Earth DEM of Debian's ferret-datasets, 0..360
# longitudes and no CRS, read as it comes) under NASA's Blue Marble.
PLANET=$(dirname "$OUT")
"$RELIEF" build 'NETCDF:"/usr/share/ferret-vis/data/etopo5.cdf":ROSE' -o "$PLANET/etopo5" \
  --kind elevation --overwrite
"$RELIEF" build data/imagery/earth-blue-marble-4096.jpg -o "$PLANET/blue-marble" --kind imagery \
  --overwrite
"$RELIEF" render "$PLANET/etopo5" --imagery "$PLANET/blue-marble" --camera 5,30,9000000,0,-90,0 \
  --size 1280x960 -o "$PLANET/earth.png"
# A 6 s H.264 movie from orbit down into the Pyrenees, every frame complete:
# the Pyrenees pyramid (level 10) fused at draw time into ETOPO5 (level 4),
# so the descent ends on SRTM detail (docs/rendering.md, "Layers of
# different depths").
"$RELIEF" render "$PLANET/etopo5" --elevation "$OUT" --camera 1.5,41.2,150000,0,-35,0 \
  --size 1280x720 -o "$PLANET/planet-pyrenees.png"
"$RELIEF" render "$PLANET/etopo5" --elevation "$OUT" --imagery "$PLANET/blue-marble" \
  --path data/paths/orbit-to-pyrenees.json --size 960x540 -o "$PLANET/planet-flight.mp4"

SAR=$(dirname "$OUT")/umbra
rm -rf "$SAR" "$SAR-lee" "$SAR-grey"
"$RELIEF" build data/sar/umbra_mount_yasur.tif -o "$SAR" --kind sar
"$RELIEF" process "$SAR" -o "$SAR-lee" --op lee --param radius=2
"$RELIEF" process "$SAR-lee" -o "$SAR-grey" --op ext-schlick --param d=0.7
"$RELIEF" detect data/sar/umbra_mount_yasur.tif -o "$SAR-targets.geojson" \
  --analysis "$SAR-target.json" --plot "$SAR-target.png"
# The same processing at draw time on the GPU (the raw store, Lee and a linear
# mapping per visible quad), draped on the ellipsoid, with the detector's hints.
"$RELIEF" render --texture "$SAR" --texture-op lee --texture-param radius=3 --texture-op linear \
  --detect --detect-level 0.25 --look-at 169.4490,-19.5308,0,600,0,-90 --size 1024x768 \
  -o "$SAR-drawtime.png"
