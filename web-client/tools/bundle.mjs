// The page's code as a few minified files: esbuild bundles src/app.js (and
// the tessellation worker, src/tess-worker.js) with the parts of three.js
// they use, tree-shaken and minified, split so that what the page imports
// lazily (the VR controller models' glTF loader) stays in its own chunk.
// Written at install (package.json "postinstall", after `npm ci`) to
// dist/<sources>/, where <sources> is the hash of the client's own modules
// and three's version (sourcesHash below; the server computes the same,
// server/src/web.rs), with brotli and gzip copies and a manifest.json. The
// server serves the bundle when a folder for the current sources exists and
// the plain modules otherwise, so a developer editing src/ never gets a
// stale page.
//
// Why bundle: measured on the demo's cold load at 2 Mbit/s (BENCHMARKS.md,
// issue 18), three's two modules are 314 KB as brotli unminified, the
// client's own 33 modules ≈ 100 KB gzipped; the bundle is ≈ 190 KB in all.
//
//   node tools/bundle.mjs

import { build } from 'esbuild';
import { existsSync, mkdirSync, readdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { brotliCompressSync, constants, gzipSync } from 'node:zlib';
import { webDir } from './module-graph.mjs';

/** FNV-1a, 64 bits, as 16 hex digits: the server's content_hash (web.rs). */
export function contentHash(bytes) {
  let h = 0xcbf29ce484222325n;
  for (const b of bytes) {
    h ^= BigInt(b);
    h = (h * 0x100000001b3n) & 0xffffffffffffffffn;
  }
  return h.toString(16).padStart(16, '0');
}

/**
 * The hash that names a bundle: of one line `/src/NAME.js HASH` per own
 * module (sorted by name, HASH its contentHash) and a last line
 * `three@VERSION`, each ending in a newline.
 */
export function sourcesHash(dir = webDir) {
  const names = readdirSync(join(dir, 'src')).filter((n) => n.endsWith('.js')).sort();
  let text = '';
  for (const n of names) text += `/src/${n} ${contentHash(readFileSync(join(dir, 'src', n)))}\n`;
  const three = JSON.parse(readFileSync(join(dir, 'node_modules/three/package.json'), 'utf8')).version;
  text += `three@${three}\n`;
  return contentHash(Buffer.from(text, 'utf8'));
}

async function main() {
  const started = performance.now();
  const sources = sourcesHash();
  const dist = join(webDir, 'dist');
  const out = join(dist, sources);
  rmSync(dist, { recursive: true, force: true });
  mkdirSync(out, { recursive: true });
  const result = await build({
    absWorkingDir: webDir,
    entryPoints: { app: 'src/app.js', 'tess-worker': 'src/tess-worker.js' },
    bundle: true,
    minify: true,
    format: 'esm',
    splitting: true,
    target: 'es2022',
    outdir: out,
    entryNames: '[name]',
    chunkNames: 'chunk-[hash]',
    sourcemap: 'linked',
    legalComments: 'linked',
    metafile: true,
    logLevel: 'warning',
  });
  // What the page's entry imports statically: hinted, so it comes with the entry.
  const entry = `dist/${sources}/app.js`;
  const preload = result.metafile.outputs[entry].imports.filter((i) => i.kind === 'import-statement').map((i) => i.path.slice(`dist/${sources}/`.length));
  writeFileSync(join(out, 'manifest.json'), `${JSON.stringify({ sources, entry: 'app.js', preload }, null, 2)}\n`);
  let raw = 0;
  let br = 0;
  for (const name of readdirSync(out)) {
    if (!name.endsWith('.js')) continue;
    const file = join(out, name);
    const data = readFileSync(file);
    const packed = brotliCompressSync(data, { params: { [constants.BROTLI_PARAM_QUALITY]: 11, [constants.BROTLI_PARAM_SIZE_HINT]: data.length, [constants.BROTLI_PARAM_MODE]: constants.BROTLI_MODE_TEXT } });
    writeFileSync(`${file}.br`, packed);
    writeFileSync(`${file}.gz`, gzipSync(data, { level: 9 }));
    raw += data.length;
    br += packed.length;
  }
  if (!existsSync(join(out, 'app.js'))) throw new Error('bundle: no app.js written');
  console.log(`bundle: dist/${sources}/ ${(raw / 1024).toFixed(0)} KiB minified, ${(br / 1024).toFixed(0)} KiB as brotli, in ${((performance.now() - started) / 1000).toFixed(1)} s`);
}

if (import.meta.url === `file://${process.argv[1]}`) await main();
