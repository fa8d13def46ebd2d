// Debian's Chromium, headless, WebGL on SwiftShader (no GPU), driven by
// puppeteer-core (pinned in package.json, no browser download), in a fresh
// profile (nothing cached): what browser_view.cjs (the browser test) and
// bench/web-flight.cjs (bench/web) open relief serve's pages in.
"use strict";

const fs = require("fs");
const os = require("os");
const path = require("path");
const puppeteer = require("puppeteer-core");

const kChromium = process.env.RELIEF_CHROMIUM || "/usr/bin/chromium";

// Launches the browser with a width x height viewport (device scale 1).
// Returns {browser, close}; close() ends the browser and removes the profile.
// Throws when the browser is missing.
async function launchChromium(width, height) {
  if (!fs.existsSync(kChromium)) {
    throw new Error(`${kChromium} is missing: run scripts/setup.sh (Debian package chromium)`);
  }
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "relief-chromium-"));
  const browser = await puppeteer.launch({
    executablePath: kChromium,
    headless: true,
    userDataDir: profile,
    defaultViewport: { width, height, deviceScaleFactor: 1 },
    args: [
      "--no-sandbox",
      // WebGL without a GPU: ANGLE on SwiftShader (not --disable-gpu, which
      // would leave the page without WebGL).
      "--use-angle=swiftshader",
      "--enable-unsafe-swiftshader",
      // The machine's network is closed: no background connections.
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
      "--disable-quic",
      "--no-first-run",
      `--window-size=${width},${height}`,
    ],
  });
  return {
    browser,
    close: async () => {
      await browser.close();
      fs.rmSync(profile, { recursive: true, force: true });
    },
  };
}

module.exports = { launchChromium, puppeteer };
