#!/usr/bin/env node
// Independent decoder check for relief's Terrain-RGB and Terrarium export.
//
//   node decode_dem_png.cjs REQUEST.json
//
// REQUEST.json: {"tiles": [{"file": "DIR/z/x/y.png", "encoding": "mapbox" | "terrarium",
//                           "pixels": [[i, j], ...]}, ...]}
// Prints one JSON object on stdout:
//   {"pngjs": VERSION, "tiles": [{"width", "height", "heights": [...], "alpha": [...]}]}
// Exit 2 with a one-line stderr message when a file cannot be read or decoded.
//
// The PNG is decoded by pngjs (not by relief's libpng wrapper) and heights
// are unpacked with MapLibre's own formula and factors: DEMData in
// maplibre-gl src/data/dem_data.ts,
//   unpack(r, g, b) = r * redFactor + g * greenFactor + b * blueFactor - baseShift.
'use strict';

const fs = require('fs');
const { PNG } = require('pngjs');

// dem_data.ts: const unpackVectors = {mapbox: [...], terrarium: [...]}.
const unpackVectors = {
  mapbox: [6553.6, 25.6, 0.1, 10000.0],
  terrarium: [256.0, 1.0, 1.0 / 256.0, 32768.0],
};

function unpack(r, g, b, [redFactor, greenFactor, blueFactor, baseShift]) {
  return r * redFactor + g * greenFactor + b * blueFactor - baseShift;
}

function decodeTile({ file, encoding, pixels }) {
  const factors = unpackVectors[encoding];
  if (!factors) throw new Error(`unknown encoding '${encoding}'`);
  const png = PNG.sync.read(fs.readFileSync(file));
  const heights = [];
  const alpha = [];
  for (const [i, j] of pixels) {
    if (!(i >= 0 && i < png.width && j >= 0 && j < png.height)) {
      throw new Error(`${file}: pixel ${i},${j} outside ${png.width} x ${png.height}`);
    }
    const k = (j * png.width + i) * 4;
    const d = png.data;
    heights.push(unpack(d[k], d[k + 1], d[k + 2], factors));
    alpha.push(d[k + 3]);
  }
  return { width: png.width, height: png.height, heights, alpha };
}

try {
  const request = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
  const out = {
    pngjs: require('pngjs/package.json').version,
    tiles: request.tiles.map(decodeTile),
  };
  process.stdout.write(JSON.stringify(out));
} catch (e) {
  process.stderr.write(`decode_dem_png: ${String((e && e.message) || e).split('\n')[0]}\n`);
  process.exit(2);
}
