#!/usr/bin/env node
// relief serve's /view/ page drapes the served imagery when its switch is
// turned on: in Debian's headless Chromium (as browser_view.cjs), opens
// `url`, waits for the terrain to be ready, screenshots, turns the imagery
// on, waits until every tile is loaded again, screenshots. Used by
// tests/web/browser_test.cpp.
//
//   node browser_imagery.cjs REQUEST.json    REQUEST: {url, width, height, timeoutMs}
//
// Prints {responses: [{path, status}] of the /imagery* requests, changed: the
// share of pixels whose colour moved by more than 8 levels}.
"use strict";

const fs = require("fs");
const { PNG } = require("pngjs");
const { openReady, fail: failNamed } = require("./chromium.cjs");

const fail = (message) => failNamed("browser_imagery", message);

async function screenshot(page) {
  return PNG.sync.read(Buffer.from(await page.screenshot({ type: "png" })));
}

// Resolves once the globe has had every tile loaded for `frames` frames in a row.
function settled(page, frames) {
  return page.evaluate(
    (frames) =>
      new Promise((resolve) => {
        let stable = 0;
        const step = () => {
          stable = relief.viewer.scene.globe.tilesLoaded ? stable + 1 : 0;
          if (stable >= frames) resolve();
          else requestAnimationFrame(step);
        };
        requestAnimationFrame(step);
      }),
    frames,
  );
}

async function main() {
  const request = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const { page, consoleLines, close } = await openReady("browser_imagery", request);
  try {
    const responses = [];
    page.on("response", (r) => {
      const path = new URL(r.url()).pathname;
      if (path.startsWith("/imagery")) responses.push({ path, status: r.status() });
    });
    await settled(page, 10);
    const before = await screenshot(page);
    await page.waitForFunction(() => !document.getElementById("imagery").disabled, {
      timeout: request.timeoutMs,
    });
    const layers = await page.evaluate(() => relief.viewer.imageryLayers.length);
    await page.click("#imagery");
    await page.waitForFunction((n) => relief.viewer.imageryLayers.length > n, { timeout: request.timeoutMs }, layers);
    await settled(page, 20);
    const after = await screenshot(page);
    let changed = 0;
    for (let i = 0; i < before.data.length; i += 4) {
      for (let c = 0; c < 3; ++c) {
        if (Math.abs(before.data[i + c] - after.data[i + c]) > 8) {
          ++changed;
          break;
        }
      }
    }
    process.stdout.write(
      JSON.stringify({ responses, changed: changed / (before.data.length / 4), console: consoleLines }) + "\n",
    );
  } catch (e) {
    await close();
    fail(`${e.message}\n${consoleLines.join("\n")}`);
  }
  await close();
}

main().catch((e) => fail(e.stack || String(e)));
