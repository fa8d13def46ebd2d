// Debian's Chromium, headless, WebGL on SwiftShader (no GPU), driven by
// puppeteer-core (pinned in package.json, no browser download): a page of
// relief serve opened and waited for until its window.relief says ready.
// Shared by browser_view.cjs, browser_map.cjs and bench/web-flight.cjs.
"use strict";

const fs = require("fs");
const os = require("os");
const path = require("path");
const puppeteer = require("puppeteer-core");

const kChromium = process.env.RELIEF_CHROMIUM || "/usr/bin/chromium";

function fail(name, message) {
  process.stderr.write(`${name}: ${message}\n`);
  process.exit(1);
}

// Launches the browser with a width x height viewport (device scale 1) in a
// fresh profile (nothing cached). Returns {browser, close}; close() ends the
// browser and removes the profile. Throws when the browser is missing.
async function launchChromium(width, height) {
  if (!fs.existsSync(kChromium)) {
    throw new Error(`${kChromium} is missing: run scripts/setup.sh --web (Debian package chromium)`);
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

// Opens request.url at request.width x request.height and waits up to
// request.timeoutMs for window.relief.ready; a failed page or a timeout
// ends the process with a message naming `name`. Returns {page,
// consoleLines, timings, lap, close}.
async function openReady(name, request) {
  if (!fs.existsSync(kChromium)) {
    fail(name, `${kChromium} is missing: run scripts/setup.sh --web (Debian package chromium)`);
  }
  const timings = {};
  const t0 = Date.now();
  const lap = (what) => (timings[what] = Date.now() - t0);
  const { browser, close } = await launchChromium(request.width, request.height);
  lap("launched");
  const page = await browser.newPage();
  const consoleLines = [];
  page.on("console", (m) => consoleLines.push(`${m.type()}: ${m.text()}`));
  // A script that fails before the page's error listener exists (a library
  // missing, say) ends the wait at once instead of at the timeout.
  let pageError;
  const pageFailed = new Promise((resolve, reject) => (pageError = reject));
  pageFailed.catch(() => {});
  page.on("pageerror", (e) => {
    consoleLines.push(`pageerror: ${e.message}`);
    pageError(e);
  });
  const failAndClose = async (message) => {
    await close();
    fail(name, `${message}\n${consoleLines.join("\n")}`);
  };
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
    if (e && !(e instanceof puppeteer.TimeoutError)) await failAndClose(`the page failed: ${e.message}`);
    const s = await page.evaluate(() =>
      window.relief
        ? { tilesLoaded: relief.tilesLoaded, pending: relief.pending, requests: relief.requests }
        : null,
    );
    await failAndClose(`window.relief.ready not true within ${request.timeoutMs} ms (${JSON.stringify(s)})`);
  }
  const error = await page.evaluate(() => window.relief.error);
  if (error) await failAndClose(`the page failed: ${error}`);
  lap("ready");
  return { page, consoleLines, timings, lap, close };
}

module.exports = { launchChromium, openReady, fail, puppeteer };
