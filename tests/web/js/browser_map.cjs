#!/usr/bin/env node
// relief serve's /map/ page (MapLibre GL JS) in a real browser (chromium.cjs).
// Used by tests/web/browser_test.cpp.
//
//   node browser_map.cjs REQUEST.json
//
// REQUEST: {url, width, height, timeoutMs, count, radius}
// Opens `url` (…/map/#camera=…), waits for window.relief.ready (MapLibre
// idle with every tile loaded), then asks MapLibre for the terrain's height
// (map.queryTerrainElevation: the DEM tiles it loaded, at the finest zoom of
// the view) at `count` points within `radius` degrees of the map's centre
// (the ground the camera looks at), placed by a fixed pseudo-random walk. Prints
// one JSON object; exits non-zero with a message when the page fails.
"use strict";

const fs = require("fs");
const { openReady } = require("./chromium.cjs");

async function main() {
  const request = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const { page, consoleLines, timings, lap, close } = await openReady("browser_map", request);
  try {
    const result = await page.evaluate((count, radius) => {
      const map = relief.map;
      const centre = map.getCenter();
      let seed = 12345;
      const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648) * 2 - 1;
      const points = [];
      for (let i = 0; i < count; ++i) points.push([centre.lng + radius * random(), centre.lat + radius * random()]);
      return {
        points,
        ready: relief.ready,
        tilesLoaded: relief.tilesLoaded,
        requests: relief.requests,
        bytes: relief.bytes,
        zoom: map.getZoom(),
        pitch: map.getPitch(),
        terrain: !!map.getTerrain(),
        heights: points.map((p) => map.queryTerrainElevation(p)),
      };
    }, request.count, request.radius);
    lap("sampled");
    process.stdout.write(JSON.stringify({ ...result, timings, console: consoleLines }) + "\n");
  } finally {
    await close();
  }
}

main().catch((e) => {
  process.stderr.write(`browser_map: ${e.stack || e}\n`);
  process.exit(1);
});
