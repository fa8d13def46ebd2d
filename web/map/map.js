// relief serve's heights in MapLibre GL JS (docs/web.md, "Pages"): a
// raster-dem source of /terrain-rgb/ drives both the 3-D terrain and a
// hillshade layer; /imagery/ is drawn on top when the server has it.
//
// The URL fragment sets the view in relief render's terms:
//   #camera=LON,LAT,HEIGHT,HEADING,PITCH[,ROLL]   degrees, metres; pitch -90
//        looks straight down (MapLibre's pitch 0); MapLibre has no roll
//   &exaggeration=X
//
// window.relief: {ready, tilesLoaded, requests, bytes, error, map}: ready
// once MapLibre is idle (every tile of the view loaded, nothing moving);
// requests and bytes count the /terrain-rgb/ and /imagery/ tiles fetched.
"use strict";

(async function () {
  const state = { ready: false, tilesLoaded: false, requests: 0, bytes: 0, error: null, map: null };
  window.relief = state;
  const status = document.getElementById("status");
  const fail = (why) => {
    state.error = String(why);
    status.textContent = state.error;
  };

  const params = new URLSearchParams(location.hash.replace(/^#/, ""));
  const numbers = (name) => (params.get(name) || "").split(",").filter((s) => s !== "").map(Number);
  const camera = numbers("camera");
  const exaggeration = numbers("exaggeration")[0] ?? 1;
  if (camera.length && (camera.length < 5 || !camera.every(Number.isFinite))) {
    return fail(`#camera=${params.get("camera")}: expected LON,LAT,HEIGHT,HEADING,PITCH[,ROLL]`);
  }

  // Tile fetches, as the browser saw them (same origin: sizes are visible).
  new PerformanceObserver((list) => {
    for (const e of list.getEntries()) {
      const path = new URL(e.name).pathname;
      if (!/^\/(terrain-rgb|imagery)\//.test(path) || path.endsWith(".json")) continue;
      ++state.requests;
      state.bytes += e.encodedBodySize || 0;
    }
  }).observe({ type: "resource", buffered: true });

  const description = async (path) => {
    const r = await fetch(path);
    return r.ok ? r.json() : null;
  };
  const dem = await description("/terrain-rgb/tiles.json");
  if (!dem) return fail("this server has no /terrain-rgb/ (an elevation store is needed)");
  const imagery = await description("/imagery/tiles.json");
  const tiles = (prefix) => [`${location.origin}${prefix}{z}/{x}/{y}.png`];
  const demSource = {
    type: "raster-dem",
    tiles: tiles("/terrain-rgb/"),
    tileSize: dem.tileSize || 256,
    encoding: "mapbox",
    minzoom: dem.minzoom,
    maxzoom: dem.maxzoom,
    bounds: dem.bounds,
  };
  const style = {
    version: 8,
    sources: { dem: demSource, shade: { ...demSource } },
    layers: [
      { id: "ground", type: "background", paint: { "background-color": "#d9d3c3" } },
      { id: "hillshade", type: "hillshade", source: "shade", paint: { "hillshade-exaggeration": 0.6 } },
    ],
    terrain: { source: "dem", exaggeration },
  };
  if (imagery) {
    style.sources.imagery = {
      type: "raster",
      tiles: tiles("/imagery/"),
      tileSize: imagery.tileSize || 256,
      minzoom: imagery.minzoom,
      maxzoom: imagery.maxzoom,
      bounds: imagery.bounds,
    };
    style.layers.push({ id: "imagery", type: "raster", source: "imagery" });
  }
  const b = dem.bounds;
  const map = new maplibregl.Map({
    container: "map",
    style,
    bounds: [
      [b[0], b[1]],
      [b[2], b[3]],
    ],
    maxPitch: 85,
    attributionControl: false,
  });
  state.map = map;
  map.on("error", (e) => fail(e.error ? e.error.message : e));
  // The camera once the first view is in: MapLibre 5.24's jumpTo at "load"
  // fails in its matrices (a null inverse) while the terrain is not there.
  let placed = !camera.length;
  const place = () => {
    placed = true;
    const [lon, lat, height, heading, pitch] = camera;
    const o = map.calculateCameraOptionsFromCameraLngLatAltRotation([lon, lat], height, heading, 90 + pitch);
    map.jumpTo({ center: o.center, zoom: o.zoom, bearing: o.bearing, pitch: o.pitch });
  };
  map.on("idle", () => {
    if (!placed) return place();
    state.tilesLoaded = map.areTilesLoaded();
    state.ready = state.tilesLoaded && map.loaded();
    status.textContent = `${state.requests} tiles, ${(state.bytes / 1048576).toFixed(1)} MiB`;
  });
  map.on("movestart", () => (state.ready = false));

  const imageryBox = document.getElementById("imagery");
  imageryBox.disabled = !imagery;
  imageryBox.addEventListener("change", () =>
    map.setLayoutProperty("imagery", "visibility", imageryBox.checked ? "visible" : "none"),
  );
  const slider = document.getElementById("exaggeration");
  slider.value = exaggeration;
  slider.addEventListener("input", () => map.setTerrain({ source: "dem", exaggeration: Number(slider.value) }));
})().catch((e) => {
  window.relief.error = String(e && e.message ? e.message : e);
});
