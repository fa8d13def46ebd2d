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
const { launchChromium, puppeteer } = require("./chromium.cjs");

function fail(message) {
  process.stderr.write(`browser_view: ${message}\n`);
  process.exit(1);
}

async function main() {
  const request = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const timings = {};
  const t0 = Date.now();
  const lap = (name) => (timings[name] = Date.now() - t0);
  let chromium;
  try {
    chromium = await launchChromium(request.width, request.height);
  } catch (e) {
    fail(e.message);
  }
  const { browser } = chromium;
  try {
    lap("launched");
    const page = await browser.newPage();
    const consoleLines = [];
    page.on("console", (m) => consoleLines.push(`${m.type()}: ${m.text()}`));
    // A script that fails before the page's error listener exists (Cesium.js
    // missing, say) ends the wait at once instead of at the timeout.
    let pageError;
    const pageFailed = new Promise((resolve, reject) => (pageError = reject));
    pageFailed.catch(() => {});
    page.on("pageerror", (e) => {
      consoleLines.push(`pageerror: ${e.message}`);
      pageError(e);
    });
    await page.goto(request.url, { waitUntil: "load", timeout: request.timeoutMs });
    lap("loaded");
    try {
      await Promise.race([
        page.waitForFunction(() => window.relief && (window.relief.ready || window.relief.error), {
          timeout: request.timeoutMs,
          polling: 100,
        }),
        pageFailed,
      ]);
    } catch (e) {
      if (e && !(e instanceof puppeteer.TimeoutError)) {
        fail(`the page failed: ${e.message}\n${consoleLines.join("\n")}`);
      }
      const s = await page.evaluate(() =>
        window.relief
          ? { tilesLoaded: relief.tilesLoaded, pending: relief.pending, requests: relief.requests }
          : null,
      );
      fail(
        `window.relief.ready not true within ${request.timeoutMs} ms (${JSON.stringify(s)})\n` +
          consoleLines.join("\n"),
      );
    }
    const error = await page.evaluate(() => window.relief.error);
    if (error) fail(`the page failed: ${error}\n${consoleLines.join("\n")}`);
    lap("ready");
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
    await chromium.close();
  }
}

main().catch((e) => fail(e.stack || String(e)));
