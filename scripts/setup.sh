#!/usr/bin/env bash
# Installs every build, test and benchmark dependency from Debian packages.
#   scripts/setup.sh         what building relief and scripts/demo.sh need
#   scripts/setup.sh --web   also relief serve's page libraries (CesiumJS,
#                            MapLibre) and the web tests' browser and
#                            decoders (the README's test command; CI)
set -euo pipefail
web=0
case ${1:-} in
  --web) web=1 ;;
  "") ;;
  *) echo "setup.sh: unknown argument '$1' (--web, or nothing)" >&2; exit 2 ;;
esac
packages=(
  build-essential cmake ninja-build ccache pkg-config git zip clang-format time python3
  libgdal-dev gdal-bin python3-gdal
  libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri
  nginx-light apache2-utils wrk libcurl4-openssl-dev
  libzstd-dev libjemalloc-dev liblerc-dev libpng-dev libturbojpeg0-dev libwebp-dev
  nlohmann-json3-dev libfmt-dev libgtest-dev
  otb-bin
  libglfw3-dev libimgui-dev xvfb xauth                                   # relief view (libs/window)
  libavcodec-dev libavformat-dev libswscale-dev libavutil-dev ffmpeg     # movies (libs/video); ffprobe in tests
  libopenmpi-dev openmpi-bin                                             # cluster rendering (libs/parallel)
  ferret-datasets                                                        # ETOPO5, the whole-Earth DEM of the main job
  clang-19 libclang-rt-19-dev  # fuzz/: libFuzzer (clang >= 16 compiles <expected>)
)
# Node.js runs the web tests' independent decoders (CesiumJS, loaders.gl) and
# drives the browser (Debian's chromium: tests/web/browser_test.cpp); the
# machine image brings node 20 from NodeSource. Only where there is none
# does Debian's (older) nodejs come in.
if ((web)); then
  packages+=(chromium)
  command -v npm >/dev/null || packages+=(nodejs npm)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# JavaScript packages, exact versions from the committed package-lock.json
# files (the npm registry; no download at test time): the libraries relief
# serve's pages load (web/, served under /lib/) and the web tests' decoders
# and browser driver (tests/web/js; puppeteer-core drives Debian's chromium
# and downloads no browser).
if ((web)); then
  npm ci --prefix web --no-audit --no-fund --loglevel=error
  npm ci --prefix tests/web/js --no-audit --no-fund --loglevel=error
fi
