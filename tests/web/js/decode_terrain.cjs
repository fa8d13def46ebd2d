#!/usr/bin/env node
// Independent decoder check for relief's quantized-mesh-1.0 export.
//
//   node decode_terrain.cjs DIR|URL REQUEST.json
//
// URL: a server's terrain root, e.g. http://127.0.0.1:8080/terrain/ (relief serve).
//
// REQUEST.json: {"level": L, "points": [[lonDeg, latDeg], ...], "tiles": [[z, x, yTms], ...]}
// Prints one JSON object on stdout. Exit 0 when every requested tile decoded;
// exit 1 (JSON still printed) when some tile has an "error" field; exit 2 with a
// one-line stderr message when the tileset itself could not be opened.
//
// DIR is served over loopback HTTP so that CesiumJS reads it exactly as a browser
// would (layer.json, Content-Encoding: gzip), while loaders.gl reads the files directly.
'use strict';

const fs = require('fs');
const http = require('http');
const path = require('path');
const zlib = require('zlib');
const Cesium = require('cesium');
const { parse } = require('@loaders.gl/core');
const { QuantizedMeshLoader } = require('@loaders.gl/terrain');

const MAX_SHORT = 32767;

// --- static server ----------------------------------------------------------
function serve(root) {
  const server = http.createServer((req, res) => {
    const rel = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    const file = path.resolve(root, '.' + rel);
    const headers = { 'Access-Control-Allow-Origin': '*' };
    // Stay inside root, and only regular files.
    if (!file.startsWith(path.resolve(root) + path.sep) || !fs.existsSync(file) ||
        !fs.statSync(file).isFile()) {
      res.writeHead(404, headers).end('not found');
      return;
    }
    if (file.endsWith('.terrain')) {
      // Files are gzip on disk; the client (undici fetch inside Cesium) inflates them.
      headers['Content-Type'] = 'application/vnd.quantized-mesh';
      headers['Content-Encoding'] = 'gzip';
    } else if (file.endsWith('.json')) {
      headers['Content-Type'] = 'application/json';
    } else {
      headers['Content-Type'] = 'application/octet-stream';
    }
    res.writeHead(200, headers).end(fs.readFileSync(file));
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

// --- helpers ------------------------------------------------------------------
const finite = (v) => (Number.isFinite(v) ? v : null);             // NaN/undefined -> null
const xyz = (c) => (c ? [finite(c.x), finite(c.y), finite(c.z)] : null);
const deg = Cesium.Math.toDegrees;
// Cesium rejects failed fetches with a RequestErrorEvent (statusCode, no message).
const errText = (e) => (e && e.statusCode !== undefined ? `HTTP ${e.statusCode}`
  : String((e && e.message) || e));

// Cesium returns undefined instead of a promise when its RequestScheduler is
// saturated (only for throttled requests; ours are not, but be safe).
async function requestGeometry(provider, x, y, z) {
  for (let attempt = 0; attempt < 100; ++attempt) {
    const p = provider.requestTileGeometry(x, y, z);
    if (p !== undefined) return await p;
    await new Promise((r) => setTimeout(r, 20));
  }
  throw new Error('requestTileGeometry stayed throttled');
}

// Decode the tile's vertices the way createVerticesFromQuantizedTerrainMesh does:
// u, v, h in 0..32767 lerped over the tile rectangle (radians) and [min, max] height.
function decodeVertices(td, rect) {
  const q = td._quantizedVertices;
  const n = q.length / 3;
  const carto = [];
  for (let i = 0; i < n; ++i) {
    carto.push(new Cesium.Cartographic(
      Cesium.Math.lerp(rect.west, rect.east, q[i] / MAX_SHORT),
      Cesium.Math.lerp(rect.south, rect.north, q[n + i] / MAX_SHORT),
      Cesium.Math.lerp(td._minimumHeight, td._maximumHeight, q[2 * n + i] / MAX_SHORT)));
  }
  return carto;
}

function cesiumReport(td, rect) {
  const ell = Cesium.Ellipsoid.WGS84;
  const carto = decodeVertices(td, rect);
  const flat = [];
  for (const c of carto) {
    const p = ell.cartographicToCartesian(c);
    flat.push(p.x, p.y, p.z);
  }
  const occluder = new Cesium.EllipsoidalOccluder(ell);
  // Direction as HeightmapTerrainData uses it: ECEF of Rectangle.center at height 0.
  const dirRectCentre = ell.cartographicToCartesian(Cesium.Rectangle.center(rect));
  const hopRecomputed = occluder.computeHorizonCullingPointFromVertices(dirRectCentre, flat, 3);
  // Is the header HOP conservative? Recompute along the header's own direction
  // (scaled-space HOP * radii = world-space direction) and compare magnitudes.
  const hop = td._horizonOcclusionPoint;
  let hopCovers = null;
  if (Number.isFinite(hop.x + hop.y + hop.z) && Cesium.Cartesian3.magnitude(hop) > 0) {
    const along = occluder.computeHorizonCullingPointFromVertices(
      Cesium.Cartesian3.multiplyComponents(hop, ell.radii, new Cesium.Cartesian3()), flat, 3);
    hopCovers = along !== undefined &&
      Cesium.Cartesian3.magnitude(hop) >= Cesium.Cartesian3.magnitude(along) * (1 - 1e-12);
  }
  // What Cesium actually culls with at run time: the header HOP, except when the
  // tile dips below the ellipsoid, where the worker recomputes it against a shrunk
  // ellipsoid using the bounding-sphere centre as direction.
  const used = td._minimumHeight < 0
    ? occluder.computeHorizonCullingPointFromVerticesPossiblyUnderEllipsoid(
      td._boundingSphere.center, flat, 3, undefined, td._minimumHeight)
    : hop;
  return {
    vertexCount: td._quantizedVertices.length / 3,
    triangleCount: td._indices.length / 3,
    minimumHeight: td._minimumHeight,
    maximumHeight: td._maximumHeight,
    horizonOcclusionPoint: xyz(hop),
    hopRecomputed: xyz(hopRecomputed),
    hopHeaderCoversVertices: hopCovers,
    hopUsedByCesium: xyz(used),
    boundingSphere: { center: xyz(td._boundingSphere.center), radius: td._boundingSphere.radius },
    westIndices: td._westIndices.length,
    southIndices: td._southIndices.length,
    eastIndices: td._eastIndices.length,
    northIndices: td._northIndices.length,
    hasEncodedNormals: td._encodedNormals !== undefined,
    encodedNormalsLength: td._encodedNormals ? td._encodedNormals.length : 0,
    firstVertices: carto.slice(0, 5).map((c) => [deg(c.longitude), deg(c.latitude), c.height]),
  };
}

// loaders.gl's public parse() only decodes through the triangle indices and hides
// the header; its internal full decoder (pinned version, so the path is stable) also
// reads the header, edge lists and extensions. Loaded via file path because the
// package "exports" map does not expose it.
let lgDecode;
async function loadersDecoder() {
  if (!lgDecode) {
    const file = path.join(path.dirname(require.resolve('@loaders.gl/terrain')),
      'lib', 'decode-quantized-mesh.js');
    lgDecode = (await import(require('url').pathToFileURL(file).href)).default;
  }
  return lgDecode;
}

// The tile's uncompressed bytes: from a file (gzip on disk) or from a server
// (fetch undoes its Content-Encoding: gzip).
async function tileBytes(source, z, x, y) {
  if (!source.startsWith('http')) return zlib.gunzipSync(fs.readFileSync(path.join(source, `${z}`, `${x}`, `${y}.terrain`)));
  const response = await fetch(`${source}${z}/${x}/${y}.terrain`);
  if (!response.ok) throw new Error(`HTTP ${response.status}`);
  return Buffer.from(await response.arrayBuffer());
}

async function loadersReport(raw, rectDeg) {
  // loaders.gl indexes dataView.buffer from 0, ignoring byteOffset: a Node Buffer
  // (pooled, non-zero offset) must be copied into its own ArrayBuffer.
  const copy = () => raw.buffer.slice(raw.byteOffset, raw.byteOffset + raw.byteLength);
  const mesh = await parse(copy(), QuantizedMeshLoader,
    { core: { worker: false }, 'quantized-mesh': { bounds: rectDeg } });
  const pos = mesh.attributes.POSITION.value;                       // Float32 lon, lat, h
  const full = (await loadersDecoder())(copy());
  const first = [];
  for (let i = 0; i < Math.min(5, pos.length / 3); ++i) first.push([pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]]);
  return {
    vertexCount: pos.length / 3,
    triangleCount: mesh.indices.value.length / 3,
    minHeight: full.header.minHeight,
    maxHeight: full.header.maxHeight,
    horizonOcclusionPoint: [full.header.horizonOcclusionPointX, full.header.horizonOcclusionPointY,
      full.header.horizonOcclusionPointZ].map(finite),
    boundingBox: mesh.header.boundingBox,                             // from decoded vertices
    edges: [full.westIndices, full.southIndices, full.eastIndices, full.northIndices].map((a) => a.length),
    vertexNormalsLength: full.extensions.vertexNormals ? full.extensions.vertexNormals.length : 0,
    firstVertices: first,
  };
}

// --- main ---------------------------------------------------------------------
async function main() {
  const [dir, reqFile] = process.argv.slice(2);
  if (!dir || !reqFile) throw new Error('usage: node decode_terrain.cjs DIR|URL REQUEST.json');
  const request = JSON.parse(fs.readFileSync(reqFile, 'utf8'));
  // A URL (relief serve's /terrain/) is read as it is; a directory is served here.
  const remote = dir.startsWith('http://');
  const server = remote ? null : await serve(dir);
  let failed = 0;
  let out;
  try {
    const url = remote ? dir : `http://127.0.0.1:${server.address().port}/`;
    let provider;
    try {
      provider = await Cesium.CesiumTerrainProvider.fromUrl(url, { requestVertexNormals: true });
    } catch (e) {
      throw new Error(`CesiumTerrainProvider.fromUrl failed: ${errText(e)}`);
    }
    // A 404 on layer.json is not an error for Cesium: it silently assumes a legacy
    // heightmap-1.0 tileset. For us that means the export is broken.
    if (provider._heightmapStructure !== undefined) {
      throw new Error('Cesium fell back to heightmap-1.0 (layer.json missing or unreadable)');
    }
    const scheme = provider.tilingScheme;

    // sampleTerrain leaves points it cannot place untouched, so start from undefined.
    const positions = (request.points || []).map(([lon, lat]) => {
      const c = Cesium.Cartographic.fromDegrees(lon, lat);
      c.height = undefined;
      return c;
    });
    await Cesium.sampleTerrain(provider, request.level, positions);

    const tiles = [];
    for (const [z, x, y] of request.tiles || []) {
      // Cesium's tile y counts rows from the north; the files (TMS) count from the south.
      const yC = scheme.getNumberOfYTilesAtLevel(z) - 1 - y;
      const rect = scheme.tileXYToRectangle(x, yC, z);
      const rectDeg = [rect.west, rect.south, rect.east, rect.north].map(deg);
      const avail = provider.getTileDataAvailable(x, yC, z);
      const t = { z, x, y, available: avail === undefined ? null : avail, rectangle: rectDeg };
      try {
        t.cesium = cesiumReport(await requestGeometry(provider, x, yC, z), rect);
        t.loaders = await loadersReport(await tileBytes(remote ? url : dir, z, x, y), rectDeg);
      } catch (e) {
        t.error = errText(e);
        failed += 1;
      }
      tiles.push(t);
    }

    out = JSON.stringify({
      cesiumVersion: Cesium.VERSION,
      hasVertexNormals: provider.hasVertexNormals,
      heights: positions.map((c) => finite(c.height)),
      tiles,
    }) + '\n';
  } finally {
    if (server) server.close();
  }
  return { out, code: failed ? 1 : 0 };
}

main().then(
  // Exit explicitly (Cesium may leave timers alive), but only once stdout is flushed.
  ({ out, code }) => process.stdout.write(out, () => process.exit(code)),
  (e) => { process.stderr.write(`decode_terrain: ${errText(e)}\n`); process.exit(2); },
);
