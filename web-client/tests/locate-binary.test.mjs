// The test command finds the server binary where cargo put it (issue 19):
// scripts/cargo-executable.mjs picks the bin artifact (not its unit-test
// build) out of cargo's JSON messages, and the browser harness asks
// `cargo metadata` for the target directory instead of assuming target/.
// The JSON lines below are written by hand from cargo's documented
// `--message-format=json` output ("compiler-artifact" messages).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { resolve } from 'node:path';
import { webDir } from './harness.mjs';

const script = resolve(webDir, '../scripts/cargo-executable.mjs');

const artifact = (name, kind, isTest, executable) =>
  JSON.stringify({ reason: 'compiler-artifact', package_id: `path+file:///w#${name}@0.1.0`, target: { kind: [kind], crate_types: [kind], name, src_path: '/w/src/main.rs' }, profile: { opt_level: '1', debuginfo: 2, test: isTest }, features: [], filenames: [executable], executable, fresh: true });

test('the bin artifact is chosen over its unit-test build and over other binaries', () => {
  const lines = [
    JSON.stringify({ reason: 'compiler-message', message: { rendered: 'warning: x' } }),
    artifact('vsculpt-server', 'bin', true, '/shared/target/debug/deps/vsculpt_server-0123abcd'),
    artifact('vsculpt-bridge', 'bin', false, '/shared/target/debug/vsculpt-bridge'),
    artifact('vsculpt-server', 'bin', false, '/shared/target/debug/vsculpt-server'),
    JSON.stringify({ reason: 'build-finished', success: true }),
  ].join('\n');
  const out = execFileSync('node', [script, 'vsculpt-server'], { input: lines, encoding: 'utf8' });
  assert.equal(out.trim(), '/shared/target/debug/vsculpt-server');
});

test('no executable reported: exit 1 with the command that shows why', () => {
  const r = spawnSync('node', [script, 'vsculpt-server'], { input: artifact('vsculpt-server', 'bin', true, '/t/deps/x') + '\n', encoding: 'utf8' });
  assert.equal(r.status, 1);
  assert.match(r.stderr, /cargo build -p vsculpt-server/);
});

test('the harness takes the target directory from cargo, honouring CARGO_TARGET_DIR', () => {
  const dir = '/nonexistent/vsculpt-target-probe';
  const code = "import('./tests/harness.mjs').then((h) => console.log(JSON.stringify([h.cargoTargetDir(), h.serverBin, h.serverBinProblem()])))";
  const env = { ...process.env, CARGO_TARGET_DIR: dir };
  delete env.VSCULPT_SERVER_BIN;
  const [target, bin, problem] = JSON.parse(execFileSync('node', ['-e', code], { cwd: webDir, env, encoding: 'utf8' }));
  assert.equal(target, dir);
  assert.equal(bin, `${dir}/release/vsculpt-server`);
  assert.match(problem, /cargo build --release -p vsculpt-server/);
});
