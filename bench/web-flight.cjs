#!/usr/bin/env node
// bench/web's CesiumJS side: relief serve's /view/ page in headless Chromium
// (SwiftShader WebGL, a fresh profile: nothing cached) flies a relief camera
// path in real time, then waits until the view is complete and measures
// the screen-space error it drew.
//
//   node bench/web-flight.cjs REQUEST.json RESULT.json
//
// REQUEST: {url: "http://HOST:PORT" (the server or bench/web's proxy),
//   path: the path file's JSON ({"keyframes": [{time, camera, cut?}...]}),
//   width, height, fov (vertical, degrees), sky: "R,G,B",
//   maxScreenSpaceError, timeoutMs (for the view to become complete after
//   the path), pickPoints: N (optional: also choose N random pixels of the
//   final view and return the finest-level sample centres, `spacing`
//   degrees apart, under them that lie inside `extent` [W, S, E, N]),
//   points: [[lon, lat, height]...] (optional: data heights to measure the
//   final view's error against)}
//
// The camera of each frame is relief's lod::camera_at at the time since the
// first frame (linear between keyframes, longitude and heading the short way
// round, a cut jumped to), set before Cesium selects that frame's tiles
// (scene.preUpdate); frames the renderer does not make are skipped, as in
// relief view. After the path's end the camera stays at its last keyframe
// until the view is complete: no terrain tile queued, loading or in flight,
// for as many consecutive frames as window.relief.ready asks (the first of
// them is when it became complete).
//
// RESULT: {frames: [{start, end (ms since the first frame), onPath (before
//   the first frame at the path's end),
//   triangles (drawn tiles' index counts without skirts / 3),
//   trianglesWithSkirts, pixels}], pathEndMs (the start of the first frame
//   at the last keyframe), completeMs (the end of the first frame of the
//   final complete run), requests, bytes (window.relief's terrain counts),
//   picked: [[lon, lat]...], errors: [pixels | null per point], timings}
"use strict";

const fs = require("fs");
const { launchChromium, puppeteer } = require("../tests/web/js/chromium.cjs");

function fail(message) {
  process.stderr.write(`web-flight: ${message}\n`);
  process.exit(1);
}

// In the page: flies the path, resolves once the view is complete after it.
function flyInPage(keys, maxSse, timeoutMs) {
  const relief = window.relief;
  const viewer = relief.viewer;
  const scene = viewer.scene;
  const globe = scene.globe;
  globe.maximumScreenSpaceError = maxSse;

  // lod::camera_at (libs/lod/src/camera_path.cpp), the same arithmetic.
  const lerp = (a, b, s) => a + (b - a) * s;
  // std::remainder: x - n y, n the nearest integer to x / y, ties to even
  // (a turn of exactly 180 degrees goes the way relief's does).
  const remainder = (x, y) => {
    const q = x / y;
    const n = Math.abs(q - Math.trunc(q)) === 0.5 ? 2 * Math.round(q / 2) : Math.round(q);
    return x - n * y;
  };
  const lerpAngle = (a, b, s) => {
    let v = a + remainder(b - a, 360) * s;
    if (v > 180) v -= 360;
    if (v < -180) v += 360;
    return v;
  };
  const cameraAt = (t) => {
    if (t <= keys[0].time) return keys[0].camera;
    const last = keys[keys.length - 1];
    if (t >= last.time) return last.camera;
    let n = 1;
    while (keys[n].time <= t) ++n;
    const a = keys[n - 1], b = keys[n];
    if (b.cut) return a.camera;
    const s = (t - a.time) / (b.time - a.time);
    const [ca, cb] = [a.camera, b.camera];
    return [
      lerpAngle(ca[0], cb[0], s),
      lerp(ca[1], cb[1], s),
      lerp(ca[2], cb[2], s),
      lerpAngle(ca[3], cb[3], s),
      lerp(ca[4], cb[4], s),
      lerp(ca[5], cb[5], s),
    ];
  };

  const endTime = keys[keys.length - 1].time;
  const frames = [];
  let t0 = null, frameStart = 0, ended = false, pathEndMs = null;
  let quietSince = null;
  return new Promise((resolve, reject) => {
    const timer = { id: null };
    scene.preUpdate.addEventListener(() => {
      const now = performance.now();
      if (t0 === null) t0 = now;
      frameStart = now - t0;
      if (ended) return;
      const t = keys[0].time + frameStart / 1000;
      relief.setCamera(cameraAt(t));
      if (t >= endTime) {
        ended = true;
        pathEndMs = frameStart;
        timer.id = setTimeout(
          () => reject(new Error(`the view was not complete ${timeoutMs} ms after the path`)),
          timeoutMs,
        );
      }
    });
    scene.postRender.addEventListener(() => {
      if (t0 === null) return;
      const end = performance.now() - t0;
      let triangles = 0, withSkirts = 0;
      for (const tile of globe._surface._tilesToRender) {
        const mesh = tile.data && tile.data.renderedMesh;
        if (!mesh) continue;
        triangles += mesh.indexCountWithoutSkirts / 3;
        withSkirts += mesh.indices.length / 3;
      }
      frames.push({
        start: frameStart,
        end,
        onPath: !ended,
        triangles,
        trianglesWithSkirts: withSkirts,
        pixels: scene.drawingBufferWidth * scene.drawingBufferHeight,
        tilesLoaded: globe.tilesLoaded,
      });
      if (!ended) return;
      // The page's own listener (added first) has updated relief.ready for
      // this frame: quiet frames in a row, the first of them the moment.
      const quiet = relief.tilesLoaded && relief.pending === 0 &&
        viewer.terrainProvider instanceof Cesium.CesiumTerrainProvider;
      if (!quiet) quietSince = null;
      else if (quietSince === null) quietSince = end;
      if (relief.ready && quietSince !== null) {
        clearTimeout(timer.id);
        resolve({ frames, pathEndMs, completeMs: quietSince });
      }
    });
  });
}

// In the page: N random pixels (a fixed seed) of the final view picked on
// the drawn globe, each moved to the centre of the finest data sample under
// it; those inside `extent`, once each.
function pickInPage(n, spacing, extent) {
  const scene = window.relief.viewer.scene;
  let seed = 12345;
  const random = () => {  // mulberry32
    seed = (seed + 0x6d2b79f5) | 0;
    let t = Math.imul(seed ^ (seed >>> 15), 1 | seed);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  const seen = new Set();
  const points = [];
  const w = scene.drawingBufferWidth, h = scene.drawingBufferHeight;
  for (let i = 0; i < n; ++i) {
    const pixel = new Cesium.Cartesian2(Math.floor(random() * w) + 0.5, Math.floor(random() * h) + 0.5);
    const hit = scene.globe.pick(scene.camera.getPickRay(pixel), scene);
    if (!hit) continue;
    const c = Cesium.Cartographic.fromCartesian(hit);
    const lon = Cesium.Math.toDegrees(c.longitude), lat = Cesium.Math.toDegrees(c.latitude);
    const i0 = Math.floor((lon + 180) / spacing), j0 = Math.floor((90 - lat) / spacing);
    const key = `${i0},${j0}`;
    if (seen.has(key)) continue;
    seen.add(key);
    const slon = -180 + (i0 + 0.5) * spacing, slat = 90 - (j0 + 0.5) * spacing;
    if (slon < extent[0] || slat < extent[1] || slon > extent[2] || slat > extent[3]) continue;
    points.push([slon, slat]);
  }
  return points;
}

// In the page: the final view's screen-space error at each point: the data
// point (lon, lat, height) and the drawn surface's point above (lon, lat)
// (the mesh of the tile this frame drew there, as Globe.getHeight finds it
// but among the drawn tiles only), both projected, their distance in
// drawing-buffer pixels; null when no drawn tile holds the point or the data
// point is off screen.
function errorsInPage(points) {
  const scene = window.relief.viewer.scene;
  const globe = scene.globe;
  const ellipsoid = globe.ellipsoid;
  const projection = globe._surface._tileProvider.tilingScheme.projection;
  const tiles = globe._surface._tilesToRender.slice();
  const w = scene.drawingBufferWidth, h = scene.drawingBufferHeight;
  return points.map(([lon, lat, height]) => {
    const carto = Cesium.Cartographic.fromDegrees(lon, lat);
    let tile = null;
    for (const t of tiles) {
      if (Cesium.Rectangle.contains(t.rectangle, carto) && (!tile || t.level > tile.level)) tile = t;
    }
    if (!tile || !tile.data || !tile.data.renderedMesh) return null;
    const onEllipsoid = Cesium.Cartesian3.fromRadians(carto.longitude, carto.latitude, 0, ellipsoid);
    const ray = new Cesium.Ray();
    ellipsoid.geodeticSurfaceNormal(onEllipsoid, ray.direction);
    if (!ellipsoid.getSurfaceNormalIntersectionWithZAxis(onEllipsoid, 11500.0, ray.origin)) return null;
    const drawn = tile.data.pick(ray, Cesium.SceneMode.SCENE3D, projection, false, new Cesium.Cartesian3());
    if (!drawn) return null;
    const data = Cesium.Cartesian3.fromDegrees(lon, lat, height, ellipsoid);
    const a = Cesium.SceneTransforms.worldToDrawingBufferCoordinates(scene, data);
    const b = Cesium.SceneTransforms.worldToDrawingBufferCoordinates(scene, drawn);
    if (!a || !b || a.x < 0 || a.y < 0 || a.x >= w || a.y >= h) return null;
    return Math.hypot(a.x - b.x, a.y - b.y);
  });
}

async function main() {
  if (process.argv.length !== 4) fail("usage: web-flight.cjs REQUEST.json RESULT.json");
  const request = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const keys = request.path.keyframes;
  const timings = {};
  const t0 = Date.now();
  const lap = (name) => (timings[name] = Date.now() - t0);
  let chromium;
  try {
    chromium = await launchChromium(request.width, request.height);
  } catch (e) {
    fail(e.message);
  }
  const consoleLines = [];
  let failure = null;
  try {
    const page = await chromium.browser.newPage();
    page.on("console", (m) => consoleLines.push(`${m.type()}: ${m.text()}`));
    page.on("pageerror", (e) => consoleLines.push(`pageerror: ${e.message}`));
    const camera = keys[0].camera.join(",");
    await page.goto(`${request.url}/view/#camera=${camera}&fov=${request.fov}&sky=${request.sky}`, {
      waitUntil: "load",
      timeout: 60000,
    });
    lap("loaded");
    // The flight starts once the terrain provider is in place (layer.json
    // read), as relief view's starts with its level-0 tiles loaded.
    await page.waitForFunction(
      () => window.relief && (window.relief.error ||
        window.relief.viewer.terrainProvider instanceof Cesium.CesiumTerrainProvider),
      { timeout: 60000, polling: 10 },
    );
    const error = await page.evaluate(() => window.relief.error);
    if (error) throw new Error(`the page failed: ${error}`);
    lap("terrain");
    const flight = await page.evaluate(flyInPage, keys, request.maxScreenSpaceError,
      request.timeoutMs);
    lap("complete");
    const counts = await page.evaluate(() => ({ requests: relief.requests, bytes: relief.bytes }));
    let picked = [];
    if (request.pickPoints) {
      picked = await page.evaluate(pickInPage, request.pickPoints, request.spacing, request.extent);
    }
    let errors = [];
    if (request.points) errors = await page.evaluate(errorsInPage, request.points);
    lap("measured");
    fs.writeFileSync(process.argv[3],
      JSON.stringify({ ...flight, ...counts, picked, errors, timings }) + "\n");
  } catch (e) {
    failure = `${e.message}\n${consoleLines.slice(-20).join("\n")}`;
  } finally {
    await chromium.close();
  }
  if (failure) fail(failure);
}

main().catch((e) => fail(e.stack || String(e)));
