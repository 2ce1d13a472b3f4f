// What the browser tests and bench/browser-fps.mjs share: starting the real
// server on a loopback port and launching headless Chromium (SwiftShader GL).
// Not a test file itself (the runner picks only *.test.mjs).

import { execFileSync, execSync, spawn } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, symlinkSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { before, after } from 'node:test';

export const webDir = resolve(dirname(fileURLToPath(import.meta.url)), '..');

/**
 * Cargo's target directory for this workspace, wherever cargo puts it
 * (`CARGO_TARGET_DIR`, `build.target-dir` in a cargo config, or the
 * default `target/`): asked of `cargo metadata`, never assumed.
 */
export function cargoTargetDir() {
  const out = execFileSync('cargo', ['metadata', '--format-version', '1', '--no-deps'], {
    cwd: resolve(webDir, '..'),
    encoding: 'utf8',
    stdio: ['ignore', 'pipe', 'inherit'],
    maxBuffer: 64 << 20,
  });
  return JSON.parse(out).target_directory;
}

/**
 * The server binary the tests start: `VSCULPT_SERVER_BIN` when set, else the
 * release build in cargo's target directory, else its debug build.
 */
function locateServerBin() {
  if (process.env.VSCULPT_SERVER_BIN) return process.env.VSCULPT_SERVER_BIN;
  const target = cargoTargetDir();
  const release = resolve(target, 'release', 'vsculpt-server');
  const debug = resolve(target, 'debug', 'vsculpt-server');
  return existsSync(release) || !existsSync(debug) ? release : debug;
}

export const serverBin = locateServerBin();

/** Why the server binary cannot be started, naming the command that fixes it; null when it can. */
export function serverBinProblem() {
  if (existsSync(serverBin)) return null;
  if (process.env.VSCULPT_SERVER_BIN) {
    return `VSCULPT_SERVER_BIN=${serverBin} names no file: build the server with \`cargo build -p vsculpt-server\` and point VSCULPT_SERVER_BIN at the executable it reports, or unset VSCULPT_SERVER_BIN to use cargo's target directory`;
  }
  return `no server binary at ${serverBin}: run \`cargo build --release -p vsculpt-server\` (or \`scripts/test.sh\`, which builds it and runs these tests)`;
}

/**
 * Starts the server; resolves when it printed its links:
 * { child, base, editor, viewer } (editor / viewer of the demo design 1, null with --no-demo).
 * `bin` is the server executable (default: `serverBin`).
 */
export function startServer({ listen = '127.0.0.1:0', dataDir, dir = webDir, args = [], bin = serverBin }) {
  return new Promise((resolveStart, reject) => {
    const child = spawn(bin, ['--listen', listen, '--data', dataDir, '--web-dir', dir, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    const demo = !args.includes('--no-demo');
    const timer = setTimeout(() => reject(new Error(`server did not print its links:\n${out}`)), 30000);
    child.stdout.on('data', (d) => {
      out += d;
      const base = out.match(/listening on (http:\/\/\S+)/);
      const editor = out.match(/design 1 "[^"]*" editor: (\S+)/);
      const viewer = out.match(/design 1 "[^"]*" viewer: (\S+)/);
      if (base && (!demo || (editor && viewer))) {
        clearTimeout(timer);
        resolveStart({ child, base: base[1], editor: editor && editor[1], viewer: viewer && viewer[1] });
      }
    });
    child.stderr.on('data', (d) => {
      out += d;
    });
    child.on('exit', (code) => reject(new Error(`server exited (${code}):\n${out}`)));
  });
}

/** The web client at git revision `rev`, unpacked into a temporary folder sharing this tree's node_modules; `cleanup()` removes it. */
export function clientAt(rev) {
  const tmp = mkdtempSync(join(tmpdir(), 'vsculpt-client-'));
  execSync(`git archive ${rev} web-client | tar -x -C ${tmp}`, { cwd: join(webDir, '..'), stdio: ['ignore', 'ignore', 'inherit'] });
  symlinkSync(join(webDir, 'node_modules'), join(tmp, 'web-client', 'node_modules'));
  // A revision with the install-time bundle serves it, as its `npm ci` would have built it.
  if (existsSync(join(tmp, 'web-client', 'tools', 'bundle.mjs'))) execSync('node tools/bundle.mjs', { cwd: join(tmp, 'web-client'), stdio: ['ignore', 'ignore', 'inherit'] });
  return { dir: join(tmp, 'web-client'), cleanup: () => rmSync(tmp, { recursive: true, force: true }) };
}

/** Creates a design through the REST API with the admin token of `dataDir`: its id and tokens. */
export async function createDesign(server, dataDir, { name = 'design', nu = 20, nv = 15 } = {}) {
  const admin = readFileSync(join(dataDir, 'admin-token'), 'utf8').trim();
  const res = await fetch(`${server.base}/api/designs`, {
    method: 'POST',
    headers: { authorization: `Bearer ${admin}`, 'content-type': 'application/json' },
    body: JSON.stringify({ name, nu, nv }),
  });
  if (res.status !== 201) throw new Error(`create design: ${res.status} ${await res.text()}`);
  return res.json();
}

/** Stops a server from startServer and waits for it to exit. */
export async function stopServer(server) {
  if (!server || server.child.exitCode !== null) return;
  const exited = new Promise((r) => server.child.once('exit', r));
  server.child.kill('SIGTERM');
  await exited;
}

/** Headless Chromium (the Debian package) with software GL (SwiftShader) and no background networking. */
export function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
}

/**
 * Opens `url` in a new page and waits until the client has joined (its
 * snapshot of the parts) with its access and the page shell has made way for the picture; page.errors collects page errors, page.requests every URL the page
 * requested, page.warnings its console warnings. `setup(page)` runs before
 * the page loads (e.g. to route requests).
 */
export async function openClient(browser, url, setup = async () => {}) {
  const page = await browser.newPage({ viewport: { width: 1100, height: 700 } });
  const errors = [];
  const requests = [];
  const warnings = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => requests.push(r.url()));
  page.on('console', (m) => {
    if (m.type() === 'warning') warnings.push(m.text());
  });
  page.requests = requests;
  page.warnings = warnings;
  await setup(page);
  await page.goto(url);
  await page.waitForFunction(
    () => window.vsculpt && window.vsculpt.design.joined && window.vsculpt.partsView.drawings.size && window.vsculpt.state.access && !document.querySelector('#shell:not(.done)'),
    null,
    { timeout: 30000 },
  );
  page.errors = errors;
  return page;
}

/** Whether `url` stays on this machine: a loopback host (or a data: URL, or a blob: URL of a loopback origin). */
export function isLocal(url) {
  const u = new URL(url);
  if (u.protocol === 'data:') return true;
  const origin = u.protocol === 'blob:' ? new URL(u.pathname) : u;
  return ['127.0.0.1', 'localhost', '[::1]'].includes(origin.hostname);
}

/** Screen position of the selected icon's gizmo Z arrow (a point on it) and of its origin. */
export function gizmoZArrow(page) {
  return page.evaluate(() => {
    const v = window.vsculpt.view;
    const r = v.renderer.domElement.getBoundingClientRect();
    const proj = (p) => {
      const q = p.clone().project(v.camera);
      return { x: r.left + ((q.x + 1) / 2) * r.width, y: r.top + ((1 - q.y) / 2) * r.height };
    };
    const icon = window.vsculpt.state.icons.get(window.vsculpt.state.selected);
    const base = icon.role.kind === 'position' && icon.anchor.kind === 'point' ? icon.target : icon.xyz;
    const o = new v.camera.position.constructor(...base);
    // The gizmo scales with distance: its Z arrow spans about 0.1·distance·fov factor above the origin.
    const tip = o.clone();
    tip.z += v.camera.position.distanceTo(o) * 0.07;
    return { from: proj(tip), origin: proj(o) };
  });
}

/** Every surface and curve part's control points as the page holds them: { id: [x, y, z, …] } (f32 values, from the frames). */
export function shownPoints(page) {
  return page.evaluate(() =>
    Object.fromEntries([...window.vsculpt.design.parts.values()].filter((p) => p.kind === 'surface' || p.kind === 'curve').map((p) => [p.id, Array.from(p.geometry ? p.geometry.points : [])])),
  );
}

/** Every surface and curve part's control points in a design document of the REST API (`design.parts[].body`): { id: [x, y, z, …] }. */
export function documentPoints(doc) {
  return Object.fromEntries(doc.parts.filter((p) => p.body.kind === 'surface' || p.body.kind === 'curve').map((p) => [p.id, (p.body.kind === 'surface' ? p.body.surface.points : p.body.curve.points).flat()]));
}


/**
 * The usual set-up of a browser test file: registers `before`/`after` hooks
 * that check the server binary, create the artifacts folder, start a server
 * on a fresh data directory (prefix `prefix`, under the system temp folder,
 * removed afterwards) and Chromium, and hand both to `use(server, browser)`.
 * Returns the data directory.
 */
export function serverAndBrowser(prefix, use) {
  const dataDir = mkdtempSync(join(tmpdir(), prefix));
  let server;
  let browser;
  before(async () => {
    const problem = serverBinProblem();
    if (problem) throw new Error(problem);
    mkdirSync(join(webDir, 'test-artifacts'), { recursive: true });
    server = await startServer({ dataDir });
    browser = await launchChromium();
    use(server, browser);
  });
  after(async () => {
    if (browser) await browser.close();
    await stopServer(server);
    rmSync(dataDir, { recursive: true, force: true });
  });
  return dataDir;
}
