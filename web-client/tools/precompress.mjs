// Writes brotli (quality 11) and gzip (level 9) copies next to every vendored
// module a page load can fetch (tools/module-graph.mjs), so the server sends
// them compressed without compressing per request (tower-http's ServeDir
// serves `file.br` / `file.gz` to a browser that accepts them, and the file
// itself to one that does not). Runs after `npm ci` (package.json
// "postinstall"); a copy newer than its source is kept, so a rerun is cheap.
// The client's own files are small and change while a developer works: the
// server compresses those per request instead.
//
//   node tools/precompress.mjs

import { readFileSync, statSync, writeFileSync, existsSync } from 'node:fs';
import { brotliCompressSync, gzipSync, constants } from 'node:zlib';
import { fileFor, moduleGraph } from './module-graph.mjs';

const fresh = (copy, source) => existsSync(copy) && statSync(copy).mtimeMs >= statSync(source).mtimeMs;

let written = 0;
let before = 0;
let after = 0;
const started = performance.now();
for (const { url } of moduleGraph()) {
  if (!url.startsWith('/vendor/')) continue;
  const file = fileFor(url);
  const data = readFileSync(file);
  before += data.length;
  if (!fresh(`${file}.br`, file)) {
    const br = brotliCompressSync(data, {
      params: { [constants.BROTLI_PARAM_QUALITY]: 11, [constants.BROTLI_PARAM_SIZE_HINT]: data.length, [constants.BROTLI_PARAM_MODE]: constants.BROTLI_MODE_TEXT },
    });
    writeFileSync(`${file}.br`, br);
    written++;
  }
  if (!fresh(`${file}.gz`, file)) {
    writeFileSync(`${file}.gz`, gzipSync(data, { level: 9 }));
    written++;
  }
  after += statSync(`${file}.br`).size;
}
console.log(
  `precompressed vendored modules: ${(before / 1024).toFixed(0)} KiB → ${(after / 1024).toFixed(0)} KiB brotli (${written} files written in ${((performance.now() - started) / 1000).toFixed(1)} s)`,
);
