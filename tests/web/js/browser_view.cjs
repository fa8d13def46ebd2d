#!/usr/bin/env node
// relief serve's /view/ page in a real browser: Debian's Chromium, headless,
// WebGL on SwiftShader (no GPU), driven by puppeteer-core (pinned in
// package.json, no browser download). Used by tests/web/browser_test.cpp.
//
//   node browser_view.cjs REQUEST.json
//
// REQUEST: {url, width, height, screenshot, timeoutMs, points: [[lon, lat]...],
//           cameras: ["LON,LAT,H,HEADING,PITCH,ROLL", ...], fov}
// Opens `url` (…/view/#camera=…), waits for window.relief.ready, samples the
// terrain at `points` with Cesium.sampleTerrainMostDetailed, writes an RGBA
// PNG screenshot of the canvas without the page's overlays, then sets each of
// `cameras` and reads back Cesium's camera (ECEF position, direction, up,
// right and vertical field of view). Prints one JSON object; exits non-zero
// with a message when the browser or the page fails.
"use strict";

const fs = require("fs");
const { PNG } = require("pngjs");
const { openReady, fail: failNamed } = require("./chromium.cjs");

const fail = (message) => failNamed("browser_view", message);

async function main() {
  const request = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const { page, consoleLines, timings, lap, close } = await openReady("browser_view", request);
  try {
    const status = await page.evaluate(() => ({
      ready: relief.ready,
      tilesLoaded: relief.tilesLoaded,
      requests: relief.requests,
      bytes: relief.bytes,
      webgl2: relief.viewer.scene.context.webgl2,
    }));

    // The screenshot first, while the view is the one that became ready.
    await page.addStyleTag({
      content: "#panel, .cesium-viewer-bottom, .cesium-viewer-toolbar { display: none !important; }",
    });
    await page.evaluate(
      () =>
        new Promise((resolve) => {
          // Two frames drawn after the overlays went away.
          requestAnimationFrame(() => requestAnimationFrame(resolve));
        }),
    );
    const shot = await page.screenshot({ type: "png", omitBackground: false });
    const png = PNG.sync.read(Buffer.from(shot));
    // Always 8-bit RGBA, whatever Chromium wrote.
    fs.writeFileSync(
      request.screenshot,
      PNG.sync.write(png, { colorType: 6, inputColorType: 6, bitDepth: 8 }),
    );
    lap("screenshot");

    const heights = await page.evaluate(async (points) => {
      const cartographics = points.map(([lon, lat]) => Cesium.Cartographic.fromDegrees(lon, lat));
      const sampled = await Cesium.sampleTerrainMostDetailed(
        relief.viewer.terrainProvider,
        cartographics,
      );
      return sampled.map((c) => (Number.isFinite(c.height) ? c.height : null));
    }, request.points || []);
    lap("sampled");

    const cameras = [];
    for (const camera of request.cameras || []) {
      cameras.push(
        await page.evaluate(
          (camera, fov) =>
            new Promise((resolve) => {
              // After the page's own hashchange listener (registered
              // first), one frame for the frustum's field of view.
              window.addEventListener(
                "hashchange",
                () => {
                const remove = relief.viewer.scene.postRender.addEventListener(() => {
                  remove();
                  const c = relief.viewer.camera;
                  const v = (p) => [p.x, p.y, p.z];
                  resolve({
                    position: v(c.positionWC),
                    direction: v(c.directionWC),
                    up: v(c.upWC),
                    right: v(c.rightWC),
                    fovy: c.frustum.fovy,
                    aspect: c.frustum.aspectRatio,
                  });
                });
                },
                { once: true },
              );
              location.hash = `camera=${camera}&fov=${fov}`;
            }),
          camera,
          request.fov,
        ),
      );
    }
    lap("cameras");
    process.stdout.write(
      JSON.stringify({
        ...status,
        heights,
        screenshot: request.screenshot,
        cameras,
        timings,
        console: consoleLines,
      }) + "\n",
    );
  } finally {
    await close();
  }
}

main().catch((e) => fail(e.stack || String(e)));
