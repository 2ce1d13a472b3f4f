// The web client's static module graph, read from the sources the browser
// loads: index.html's import map and its entry module, then every static
// `import … from '…'` / `export … from '…'`, every module worker
// (`new URL('…', import.meta.url)`) and every dynamic `import('…')` of a
// literal path reachable from it, in the client's own files and in the
// vendored packages. Used to precompress what the page can fetch
// (tools/precompress.mjs) and to check the page's modulepreload hints against
// the graph (tests/assets.test.mjs): a lazily imported module (one reached
// only through a dynamic import, e.g. the VR controllers' glTF loader) is not
// hinted, so a cold load does not fetch it before the first picture.

import { existsSync, readFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

export const webDir = resolve(dirname(fileURLToPath(import.meta.url)), '..');

/**
 * URL prefixes the server maps to folders (web.rs): the vendored packages
 * under node_modules, then the client's own files.
 */
export const MOUNTS = [
  ['/vendor/three/', 'node_modules/three/'],
  ['/vendor/iwer/', 'node_modules/iwer/'],
  ['/vendor/webxr-profiles/', 'node_modules/@webxr-input-profiles/assets/dist/profiles/'],
  ['/', ''],
];

/** The folder path under webDir for a served URL path. */
export function fileFor(urlPath) {
  for (const [prefix, dir] of MOUNTS) if (urlPath.startsWith(prefix)) return join(webDir, dir, urlPath.slice(prefix.length));
  throw new Error(`not served: ${urlPath}`);
}

/** index.html's import map ({ specifier: url }) and the module scripts it loads. */
export function pageEntries(html = readFileSync(join(webDir, 'index.html'), 'utf8')) {
  const map = html.match(/<script type="importmap">([\s\S]*?)<\/script>/);
  const imports = map ? JSON.parse(map[1]).imports : {};
  const entries = [...html.matchAll(/<script type="module" src="([^"]+)"/g)].map((m) => m[1]);
  return { imports, entries };
}

function resolveSpecifier(spec, from, imports) {
  if (spec.startsWith('./') || spec.startsWith('../') || spec.startsWith('/')) return new URL(spec, `http://x${from}`).pathname;
  if (imports[spec]) return imports[spec];
  for (const [k, v] of Object.entries(imports)) if (k.endsWith('/') && spec.startsWith(k)) return v + spec.slice(k.length);
  throw new Error(`${from}: bare specifier "${spec}" not in the import map`);
}

const STATIC = /(?:^|[;\s])(?:import|export)\s*(?:[\w*${}\s,]+?\s*from\s*)?['"]([^'"]+)['"]/g;
const WORKER = /new\s+URL\(\s*['"]([^'"]+)['"]\s*,\s*import\.meta\.url\s*\)/g;
const DYNAMIC = /(?:^|[^\w.$])import\(\s*['"]([^'"]+)['"]\s*\)/g;

/**
 * Every module reachable from the page's entries, in discovery order:
 * [{ url, worker, lazy }], `worker` true for a module worker's script and the
 * modules only it imports (they load in the worker, not the page), `lazy`
 * true for a module reached only through a dynamic import (and what only it
 * imports): it loads when the page asks for it, not with the page.
 */
export function moduleGraph() {
  const { imports, entries } = pageEntries();
  const seen = new Map(); // url → { worker, lazy }
  const queue = entries.map((url) => ({ url, worker: false, lazy: false }));
  while (queue.length) {
    const { url, worker, lazy } = queue.shift();
    const was = seen.get(url);
    // Visited already in a way that loads it at least as early: nothing new.
    if (was && (!was.worker || worker) && (!was.lazy || lazy)) continue;
    const file = fileFor(url);
    if (!existsSync(file)) throw new Error(`${url}: no file ${file}`);
    const now = was ? { worker: was.worker && worker, lazy: was.lazy && lazy } : { worker, lazy };
    seen.set(url, now);
    const text = readFileSync(file, 'utf8').replace(/\/\*[\s\S]*?\*\//g, '').replace(/^\s*\/\/.*$/gm, '');
    for (const m of text.matchAll(STATIC)) queue.push({ url: resolveSpecifier(m[1], url, imports), worker: now.worker, lazy: now.lazy });
    for (const m of text.matchAll(WORKER)) queue.push({ url: resolveSpecifier(m[1], url, imports), worker: true, lazy: now.lazy });
    for (const m of text.matchAll(DYNAMIC)) queue.push({ url: resolveSpecifier(m[1], url, imports), worker: now.worker, lazy: true });
  }
  return [...seen].map(([url, { worker, lazy }]) => ({ url, worker, lazy }));
}
