// Screenshots of a web player folder in headless Chromium (the system's: puppeteer-core brings none).
// node web_player_shot.js CHROMIUM PLAYER_DIR OUT_PREFIX WIDTH HEIGHT T1 [T2 ...]
// For each time T: opens PLAYER_DIR/index.html?t=T&paused=1&bare=1 from file://, waits until the page
// says the frame at T is drawn and sorted (window.sffdReady) and writes OUT_PREFIX_<i>.png (the canvas
// only). Software WebGL (SwiftShader): no GPU needed. Prints one JSON line per shot; exit 1 on any
// page error, 2 on a usage error.
"use strict";
const path = require("path");
const { pathToFileURL } = require("url");

async function main() {
  const [chromium, dir, prefix, w, h, ...times] = process.argv.slice(2);
  if (!chromium || !dir || !prefix || !w || !h || times.length === 0) {
    console.error("usage: node web_player_shot.js CHROMIUM PLAYER_DIR OUT_PREFIX WIDTH HEIGHT T1 [T2 ...]");
    process.exit(2);
  }
  const puppeteer = require("puppeteer-core");
  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
           "--force-device-scale-factor=1", "--disable-gpu-vsync"],
  });
  let failed = false;
  try {
    for (let i = 0; i < times.length; ++i) {
      const page = await browser.newPage();
      const messages = [];
      page.on("console", (m) => messages.push(m.type() + ": " + m.text()));
      page.on("pageerror", (e) => messages.push("pageerror: " + e.message));
      await page.setViewport({ width: Number(w) + 16, height: Number(h) + 64, deviceScaleFactor: 1 });
      const url = pathToFileURL(path.resolve(dir, "index.html")).href + `?t=${times[i]}&paused=1&bare=1`;
      const t0 = Date.now();
      await page.goto(url, { waitUntil: "load" });
      let state;
      try {
        await page.waitForFunction("window.sffdReady === true || window.sffdError", { timeout: 120000, polling: 100 });
        state = await page.evaluate(() => ({ ready: window.sffdReady, error: window.sffdError, state: window.sffdState }));
      } catch (e) {
        state = { ready: false, error: "timed out waiting for the frame: " + e.message };
      }
      const out = `${prefix}_${i}.png`;
      if (state.ready) {
        const canvas = await page.$("#view");
        await canvas.screenshot({ path: out });
      } else failed = true;
      console.log(JSON.stringify({ time: Number(times[i]), out, ms: Date.now() - t0, ...state,
                                   messages: messages.slice(0, 20) }));
      await page.close();
    }
  } finally {
    await browser.close();
  }
  process.exit(failed ? 1 : 0);
}
main().catch((e) => { console.error(String(e && e.stack || e)); process.exit(1); });
