// relief serve's terrain in a CesiumJS viewer (docs/web.md, "Pages").
//
// The URL fragment sets the view in relief render's terms (docs/rendering.md):
//   #camera=LON,LAT,HEIGHT,HEADING,PITCH,ROLL   degrees, metres above the ellipsoid
//   &fov=DEG           vertical field of view (relief's default 60)
//   &exaggeration=X    vertical exaggeration (1)
//   &sky=R,G,B         a flat sky of exactly this colour, as relief render --sky:
//                      no sky box, atmosphere, fog, sun, moon or antialiasing,
//                      so a frame can be compared pixel by pixel
//
// window.relief reports the page's state to tests and scripts:
//   ready        every tile the view needs is loaded and drawn (stable for a
//                few frames, no terrain request pending)
//   tilesLoaded  Cesium's globe.tilesLoaded in the last frame
//   requests, bytes  terrain requests answered and their body bytes (gzip)
//   error        why the terrain could not be loaded, or null
//   viewer       the Cesium.Viewer
//   setCamera([LON, LAT, HEIGHT, HEADING, PITCH, ROLL])  the fragment's camera
//                without a hashchange (bench/web flies a path frame by frame)
"use strict";

(function () {
  const kStableFrames = 10;
  const state = {
    ready: false,
    tilesLoaded: false,
    requests: 0,
    bytes: 0,
    pending: 0,
    error: null,
    viewer: null,
  };
  window.relief = state;
  window.addEventListener("error", (e) => {
    state.error = state.error || String(e.message);
  });

  // Cesium fetches terrain with XMLHttpRequest (Resource.fetchArrayBuffer):
  // counting there sees every request, including those still in flight.
  const isTerrain = (url) => new URL(url, location.href).pathname.startsWith("/terrain/");
  const open = XMLHttpRequest.prototype.open;
  XMLHttpRequest.prototype.open = function (method, url, ...rest) {
    this.reliefTerrain = isTerrain(String(url));
    return open.call(this, method, url, ...rest);
  };
  const send = XMLHttpRequest.prototype.send;
  XMLHttpRequest.prototype.send = function (...args) {
    if (this.reliefTerrain) {
      ++state.pending;
      this.addEventListener("loadend", () => {
        --state.pending;
        ++state.requests;
        state.bytes += Number(this.getResponseHeader("Content-Length")) || 0;
      });
    }
    return send.apply(this, args);
  };

  function parseFragment() {
    const params = new URLSearchParams(location.hash.replace(/^#/, ""));
    const numbers = (name, count) => {
      const text = params.get(name);
      if (text === null) return null;
      const v = text.split(",").map(Number);
      if (v.length !== count || !v.every(Number.isFinite)) {
        throw new Error(`#${name}=${text}: expected ${count} numbers`);
      }
      return v;
    };
    return {
      camera: numbers("camera", 6),
      fov: (numbers("fov", 1) || [60])[0],
      exaggeration: (numbers("exaggeration", 1) || [1])[0],
      sky: numbers("sky", 3),
    };
  }

  let fragment = { camera: null, fov: 60, exaggeration: 1, sky: null };
  try {
    fragment = parseFragment();
  } catch (e) {
    state.error = String(e.message || e);
  }
  const flatSky = fragment.sky !== null;
  const viewer = new Cesium.Viewer("viewer", {
    baseLayer: false,
    baseLayerPicker: false,
    geocoder: false,
    timeline: false,
    animation: false,
    homeButton: false,
    sceneModePicker: false,
    navigationHelpButton: false,
    fullscreenButton: false,
    infoBox: false,
    selectionIndicator: false,
    skyBox: flatSky ? false : undefined,
    skyAtmosphere: flatSky ? false : undefined,
    msaaSamples: flatSky ? 1 : 4,
  });
  state.viewer = viewer;
  const scene = viewer.scene;
  const globe = scene.globe;
  globe.baseColor = Cesium.Color.fromBytes(196, 186, 164);
  globe.enableLighting = true;
  globe.dynamicAtmosphereLighting = false;
  if (flatSky) {
    scene.backgroundColor = Cesium.Color.fromBytes(...fragment.sky);
    scene.fog.enabled = false;
    globe.showGroundAtmosphere = false;
    // Without a sky box Cesium makes no sun or moon.
    if (scene.sun) scene.sun.show = false;
    if (scene.moon) scene.moon.show = false;
    scene.postProcessStages.fxaa.enabled = false;
  }

  // relief's camera (lod::make_view): heading clockwise from north, pitch up
  // from the horizontal, both as Cesium's; relief's positive roll turns the
  // camera's up towards its left, Cesium's towards its right.
  function setCamera(c) {
    const [lon, lat, height, heading, pitch, roll] = c;
    const destination = Cesium.Cartesian3.fromDegrees(lon, lat, height);
    viewer.camera.setView({
      destination,
      orientation: {
        heading: Cesium.Math.toRadians(heading),
        pitch: Cesium.Math.toRadians(pitch),
        roll: Cesium.Math.toRadians(-roll),
      },
    });
    // A light from the north-west, 45 degrees up, fixed in the camera's
    // local frame: the terrain's normals show whatever the clock says.
    const enu = Cesium.Transforms.eastNorthUpToFixedFrame(destination);
    const toLight = Cesium.Matrix4.multiplyByPointAsVector(
      enu,
      new Cesium.Cartesian3(-0.5, 0.5, Math.SQRT1_2),
      new Cesium.Cartesian3(),
    );
    scene.light = new Cesium.DirectionalLight({
      direction: Cesium.Cartesian3.negate(toLight, new Cesium.Cartesian3()),
    });
  }

  // relief's field of view is vertical; Cesium's PerspectiveFrustum.fov
  // spans the wider side (width when the aspect ratio is above 1).
  let fovY = Cesium.Math.toRadians(fragment.fov);
  scene.preRender.addEventListener(() => {
    const frustum = viewer.camera.frustum;
    const aspect = scene.drawingBufferWidth / scene.drawingBufferHeight;
    if (!(aspect > 0) || !(frustum instanceof Cesium.PerspectiveFrustum)) return;
    frustum.fov = aspect <= 1 ? fovY : 2 * Math.atan(Math.tan(fovY / 2) * aspect);
  });

  // Ready: the terrain provider is in place, the globe's load queues are
  // empty and no terrain request is in flight, for kStableFrames frames.
  let terrainReady = false;
  let stable = 0;
  scene.postRender.addEventListener(() => {
    state.tilesLoaded = globe.tilesLoaded;
    const quiet = terrainReady && globe.tilesLoaded && state.pending === 0;
    stable = quiet ? stable + 1 : 0;
    state.ready = stable >= kStableFrames;
  });

  // The layer panel.
  const slider = document.getElementById("exaggeration");
  const sliderValue = document.getElementById("exaggeration-value");
  function setExaggeration(x) {
    scene.verticalExaggeration = x;
    slider.value = String(x);
    sliderValue.textContent = x.toFixed(1);
  }
  slider.addEventListener("input", () => setExaggeration(Number(slider.value)));
  setExaggeration(fragment.exaggeration);

  // Imagery, when the server has one: Cesium's own geographic tiling
  // (/imagery-geo/: the store's samples as they are) where it is served,
  // else the Web Mercator XYZ tiles of /imagery/. Its absence is no error.
  const imageryBox = document.getElementById("imagery");
  const imageryLabel = document.getElementById("imagery-label");
  let imagery = null;
  const describe = (route) => fetch(route + "tiles.json").then((r) => (r.ok ? r.json() : null));
  Promise.all([describe("/imagery-geo/"), describe("/imagery/")]).then(
    ([geographic, mercator]) => {
      const description = geographic || mercator;
      if (!description) {
        imageryLabel.textContent = "Imagery (none served)";
        return;
      }
      const [west, south, east, north] = description.bounds;
      imageryBox.disabled = false;
      imageryBox.addEventListener("change", () => {
        if (imageryBox.checked) {
          imagery = viewer.imageryLayers.addImageryProvider(
            new Cesium.UrlTemplateImageryProvider({
              url: geographic ? "/imagery-geo/{z}/{x}/{y}.png" : "/imagery/{z}/{x}/{y}.png",
              tilingScheme: geographic
                ? new Cesium.GeographicTilingScheme()
                : new Cesium.WebMercatorTilingScheme(),
              maximumLevel: description.maxzoom,
              rectangle: Cesium.Rectangle.fromDegrees(west, south, east, north),
            }),
          );
        } else if (imagery) {
          viewer.imageryLayers.remove(imagery);
          imagery = null;
        }
      });
    },
    () => {},
  );

  state.setCamera = setCamera;
  if (fragment.camera) setCamera(fragment.camera);
  window.addEventListener("hashchange", () => {
    try {
      const f = parseFragment();
      fovY = Cesium.Math.toRadians(f.fov);
      if (f.camera) setCamera(f.camera);
      setExaggeration(f.exaggeration);
      stable = 0;
    } catch (e) {
      state.error = String(e.message || e);
    }
  });

  Cesium.CesiumTerrainProvider.fromUrl("/terrain/", { requestVertexNormals: true }).then(
    (provider) => {
      viewer.terrainProvider = provider;
      terrainReady = true;
    },
    (e) => {
      state.error = `the terrain at /terrain/ could not be loaded: ${e.message || e}`;
      imageryLabel.textContent = state.error;
    },
  );
})();
