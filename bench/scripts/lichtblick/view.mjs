// Lichtblick's web app in headless Chromium, driven as a person would: it connects to a
// running `rig run --live` (Open connection → Foxglove WebSocket), imports a layout
// (Layouts → Import from file…) and takes screenshots seconds apart; then, in a fresh
// profile, it opens a finished run's run.mcap (Open local file(s)…) with the same layout
// and screenshots that. The operating system's file dialog, which a headless browser does
// not have, is the only thing replaced: `showOpenFilePicker` answers with the file named,
// fetched into the page's own (origin private) file system.
//
//   node view.mjs --app DIR --files DIR --out DIR --profile DIR [--layout NAME]
//                 [--live ws://127.0.0.1:PORT] [--mcap NAME] [--settle 8] [--shots 2]
//                 [--every 3] [--chromium /usr/bin/chromium] [--verbose]
//
// --app: the built web app (Lichtblick's web/.webpack); --files: the folder of the layout
// (default live-layout.json) and the recording (served beside the app); --profile: an
// empty folder for the browser's profile; --settle: seconds live before the first shot;
// --every: seconds between shots; --verbose: the page's errors and warnings too.
//
// It checks what a person would look at and exits 1 naming what it did not see: the
// connection, a value in every plot panel's legend, the system drawn in the 3D panel
// (pixels of the picture's colours) and, live, the 3D panel changed between shots; on a
// recording the same, every panel's topics among the recording's. Writes OUT/live-N.png,
// OUT/recording.png and OUT/checks.json.
import { readFileSync } from "node:fs";
import { createServer } from "node:http";
import { mkdir, readFile, writeFile } from "node:fs/promises";
import { extname, join, normalize } from "node:path";
import { parseArgs } from "node:util";
import puppeteer from "puppeteer-core";

const { values: args } = parseArgs({
  options: {
    app: { type: "string" },
    files: { type: "string" },
    layout: { type: "string", default: "live-layout.json" },
    live: { type: "string" },
    mcap: { type: "string" },
    out: { type: "string" },
    shots: { type: "string", default: "2" },
    every: { type: "string", default: "3" },
    settle: { type: "string", default: "8" },
    chromium: { type: "string", default: "/usr/bin/chromium" },
    profile: { type: "string" },
    verbose: { type: "boolean", default: false },
    help: { type: "boolean", default: false },
  },
});
if (args.help) {
  const head = readFileSync(new URL(import.meta.url), "utf8").split("\n").filter((l) => l.startsWith("//"));
  console.log(head.map((l) => l.replace(/^\/\/ ?/, "")).join("\n"));
  process.exit(0);
}
for (const need of ["app", "files", "out", "profile"]) {
  if (!args[need]) {
    console.error(`view.mjs: --${need} is required`);
    process.exit(2);
  }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const TYPES = {
  ".html": "text/html",
  ".js": "text/javascript",
  ".wasm": "application/wasm",
  ".json": "application/json",
  ".png": "image/png",
  ".ttf": "font/ttf",
  ".ico": "image/x-icon",
};

/** The app at /, the layout and the recording at /files/NAME; this host only. */
async function serve() {
  const server = createServer(async (req, res) => {
    let path = normalize(decodeURIComponent(new URL(req.url, "http://x").pathname));
    if (path === "/") path = "/index.html";
    const file = path.startsWith("/files/")
      ? join(args.files, path.slice("/files/".length))
      : join(args.app, path);
    try {
      const body = await readFile(file);
      res.writeHead(200, { "content-type": TYPES[extname(file)] ?? "application/octet-stream" });
      res.end(body);
    } catch {
      res.writeHead(404);
      res.end();
    }
  });
  await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
  return server;
}

/** A page on the app in a fresh browser context, its file dialog answering `window.__pick`. */
async function open(browser, url) {
  const context = await browser.createBrowserContext();
  const page = await context.newPage();
  await page.setViewport({ width: 1600, height: 900 });
  page.on("pageerror", (e) => console.error(`page error: ${e.message.split("\n")[0]}`));
  if (args.verbose) {
    page.on("console", async (m) => {
      if (m.type() !== "error" && m.type() !== "warn") return;
      const text = await Promise.all(
        m.args().map((a) => a.evaluate((v) => (v instanceof Error ? v.message : JSON.stringify(v))).catch(() => "?")),
      );
      console.error(`page ${m.type()}: ${text.join(" ").slice(0, 300)}`);
    });
  }
  // The file dialog answers with real file handles: the files named, fetched from /files/
  // into the page's own file system (the origin private file system).
  await page.evaluateOnNewDocument(() => {
    window.showOpenFilePicker = async () => {
      const root = await navigator.storage.getDirectory();
      return await Promise.all(
        (window.__pick ?? []).map(async (name) => {
          const handle = await root.getFileHandle(name, { create: true });
          const writable = await handle.createWritable();
          await writable.write(await (await fetch(`/files/${name}`)).blob());
          await writable.close();
          return handle;
        }),
      );
    };
  });
  await page.goto(url, { waitUntil: "networkidle2", timeout: 120_000 });
  return { context, page };
}

/** Clicks an element matching `selector` whose text is (or starts with) `text`, waiting for one. */
async function click(page, selector, text, { prefix = false, timeout = 30_000 } = {}) {
  const t0 = Date.now();
  for (;;) {
    const done = await page.evaluate(
      (selector, text, prefix) => {
        // The innermost such element: a click on it reaches every handler around it.
        const el = [...document.querySelectorAll(selector)].findLast((e) => {
          const t = e.innerText?.trim() ?? "";
          return prefix ? t.startsWith(text) : t === text;
        });
        el?.click();
        return Boolean(el);
      },
      selector,
      text,
      prefix,
    );
    if (done) return;
    if (Date.now() - t0 > timeout) throw new Error(`no "${text}" to click (${selector})`);
    await sleep(200);
  }
}

/** Per panel of the layout, by its title (its own, else the panel type's): the topics
 * it shows. */
async function expected() {
  const layout = JSON.parse(await readFile(join(args.files, args.layout), "utf8"));
  return Object.fromEntries(
    Object.entries(layout.configById).map(([id, c]) => [
      c.foxglovePanelTitle ?? id.split("!")[0],
      [...new Set([...(c.paths ?? []).map((p) => p.value.split(".")[0]), ...Object.keys(c.topics ?? {})])],
    ]),
  );
}

/** Layouts → Import from file…, answered with the layout; then the left sidebar closed. */
async function importLayout(page) {
  console.error(`view: Layouts → Import from file… ${args.layout}`);
  await page.evaluate((name) => (window.__pick = [name]), args.layout);
  await click(page, '[role="tab"]', "Layouts");
  await click(page, '[role="button"], button', "Import from file", { prefix: true });
  const titles = Object.keys(await expected());
  for (const t0 = Date.now(); ; await sleep(200)) {
    const shown = (await panels(page)).map((p) => p.title);
    if (titles.every((t) => shown.includes(t))) break;
    if (Date.now() - t0 > 30_000) {
      throw new Error(`the layout's panels ${JSON.stringify(titles)} did not appear: ${JSON.stringify(shown)}`);
    }
  }
  // More room for the panels.
  await page.locator('[data-testid="sidebar-close-left"]').click();
}

/** Per panel of the layout: its title, its legend's values, and where it is. */
async function panels(page) {
  return await page.evaluate(() =>
    [...document.querySelectorAll(".mosaic-tile")]
      .filter((t) => !t.querySelector(".mosaic-tile"))
      .map((t) => {
        const lines = t.innerText.split("\n").map((l) => l.trim()).filter(Boolean);
        const r = t.getBoundingClientRect();
        return {
          title: lines[0] ?? "",
          values: lines.slice(1).filter((l) => /^-?\d/.test(l)).map(Number).filter(Number.isFinite),
          rect: { x: r.x, y: r.y, width: r.width, height: r.height },
        };
      }),
  );
}

/** Per screenshot (PNG) of the 3D panel: its pixels in the picture's colours
 * (rig/src/picture.rs: the links' blue, the joints' orange), and the pixels that
 * changed since the screenshot before it. */
async function look(page, shots) {
  return await page.evaluate(async (shots) => {
    const decode = async (b64) => {
      const img = new Image();
      img.src = `data:image/png;base64,${b64}`;
      await img.decode();
      const c = new OffscreenCanvas(img.width, img.height).getContext("2d");
      c.drawImage(img, 0, 0);
      return c.getImageData(0, 0, img.width, img.height).data;
    };
    const seen = [];
    let before;
    for (const shot of shots) {
      const px = await decode(shot);
      // Shaded by the scene's light: told apart by hue, not by value.
      const s = { link: 0, joint: 0, changed: 0 };
      for (let i = 0; i < px.length; i += 4) {
        const [r, g, b] = [px[i], px[i + 1], px[i + 2]];
        if (b > 150 && b - r > 100 && b - g > 50) s.link++;
        if (r > 120 && r - g > 70 && g - b > 20) s.joint++;
        if (before && (r !== before[i] || g !== before[i + 1] || b !== before[i + 2])) s.changed++;
      }
      seen.push(s);
      before = px;
    }
    return seen;
  }, shots.map((s) => s.toString("base64")));
}

/** Whether a look at the 3D panel shows the system: its links and its joints. */
const drawn = (s) => s.link > 500 && s.joint > 100;

/** The 3D panel's screenshot alone. */
async function scene(page) {
  const three = (await panels(page)).find((p) => p.title === "3D");
  if (!three) throw new Error("no 3D panel in the layout");
  return await page.screenshot({ clip: three.rect });
}

/** Waits (up to `seconds`) until every plot panel's legend shows a value; returns the panels. */
async function plotted(page, seconds) {
  const t0 = Date.now();
  let seen;
  do {
    seen = (await panels(page)).filter((p) => p.title !== "3D");
    if (seen.every((p) => p.values.length > 0)) break;
    await sleep(500);
  } while (Date.now() - t0 < seconds * 1000);
  return seen;
}

const failures = [];
const checks = {};
function check(what, ok, detail) {
  console.error(`${ok ? "ok  " : "FAIL"} ${what}: ${detail}`);
  if (!ok) failures.push(what);
  checks[what] = { ok, detail };
}

async function live(browser, base) {
  const { context, page } = await open(browser, base);
  console.error(`view: Open connection → Foxglove WebSocket ${args.live}`);
  await click(page, "*", "Open connection", { prefix: true });
  await page.locator('[role="dialog"] input[type="text"]').fill(args.live);
  await click(page, '[role="dialog"] button', "Open");
  await page.waitForFunction((url) => document.body.textContent.includes(url), { timeout: 30_000 }, args.live);
  await importLayout(page);
  const seen = await plotted(page, 30);
  // Let the plots gather some seconds of the run before the first shot.
  await sleep(Number(args.settle) * 1000);
  for (const p of seen) check(`live: ${p.title}`, p.values.length > 0, `legend values ${JSON.stringify(p.values)}`);
  const shots = [];
  for (let i = 1; i <= Number(args.shots); i++) {
    if (i > 1) await sleep(Number(args.every) * 1000);
    const path = join(args.out, `live-${i}.png`);
    await page.screenshot({ path });
    shots.push([path, await scene(page)]);
  }
  const looks = await look(page, shots.map(([, png]) => png));
  looks.forEach((s, i) => {
    const [path] = shots[i];
    check(`live shot ${i + 1}: the system drawn`, drawn(s), `${s.link} link and ${s.joint} joint pixels in the 3D panel (${path})`);
    if (i > 0) check(`live shots ${i} → ${i + 1}: the 3D panel moved`, s.changed > 200, `${s.changed} pixels differ`);
  });
  await context.close();
}

/** The topics the open data source lists (the Topics tab). */
async function topics(page) {
  await click(page, '[role="tab"]', "Topics");
  await page.waitForFunction(() => /\n\/\S/.test(document.body.innerText), { timeout: 30_000 });
  return await page.evaluate(() =>
    document.body.innerText.split("\n").map((l) => l.trim()).filter((l) => /^\/\S+$/.test(l)),
  );
}

async function recording(browser, base) {
  const { context, page } = await open(browser, base);
  console.error(`view: Open local file(s)… ${args.mcap}`);
  await page.evaluate((name) => (window.__pick = [name]), args.mcap);
  await click(page, "*", "Open local file(s)", { prefix: true });
  await page.waitForFunction((name) => document.body.textContent.includes(name), { timeout: 60_000 }, args.mcap);
  const recorded = await topics(page);
  console.error(`view: the recording's topics ${recorded.join(" ")}`);
  await importLayout(page);
  // Halfway through the recording, then a few seconds played, as a person would click
  // on the playback bar and press play.
  const play = await page.waitForSelector('button[title="Play"]', { timeout: 30_000 });
  // The playback bar spans the window just above the buttons.
  const button = await play.boundingBox();
  await page.mouse.click(800, button.y - 30);
  await sleep(2000);
  await play.click();
  await sleep(2 * Number(args.every) * 1000);
  // Every panel shows data: the recording holds every topic of the layout.
  const wanted = await expected();
  const lacking = (title) => (wanted[title] ?? []).filter((topic) => !recorded.includes(topic));
  const seen = await plotted(page, 10);
  for (const p of seen) {
    const none = lacking(p.title);
    const detail = none.length > 0 ? `not recorded: ${none.join(" ")}` : `legend values ${JSON.stringify(p.values)}`;
    check(`recording: ${p.title}`, none.length === 0 && p.values.length > 0, detail);
  }
  const path = join(args.out, "recording.png");
  await page.screenshot({ path });
  check("recording: 3D: its topics recorded", lacking("3D").length === 0, `not recorded: ${lacking("3D").join(" ") || "none"}`);
  const [s] = await look(page, [await scene(page)]);
  check("recording: the system drawn", drawn(s), `${s.link} link and ${s.joint} joint pixels in the 3D panel (${path})`);
  await context.close();
}

await mkdir(args.out, { recursive: true });
const server = await serve();
const base = `http://127.0.0.1:${server.address().port}/`;
const browser = await puppeteer.launch({
  executablePath: args.chromium,
  headless: true,
  args: [
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    `--user-data-dir=${args.profile}`,
  ],
});
try {
  if (args.live) await live(browser, base);
  if (args.mcap) await recording(browser, base);
} catch (e) {
  failures.push(e.message);
  console.error(`view.mjs: ${e.message}`);
} finally {
  await browser.close();
  server.close();
}
await writeFile(join(args.out, "checks.json"), JSON.stringify(checks, null, 2) + "\n");
if (failures.length > 0) {
  console.error(`view.mjs: not seen: ${failures.join("; ")}`);
  process.exit(1);
}
