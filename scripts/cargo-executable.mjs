// Reads cargo's `--message-format=json` output on stdin and prints the path of
// the executable cargo reports for the bin target named on the command line
// (not its unit-test build): the binary wherever cargo put it, whatever
// CARGO_TARGET_DIR or build.target-dir say. Exits 1, naming the fix, when
// cargo reported no such executable.
//   cargo build -p vsculpt-server --message-format=json | node scripts/cargo-executable.mjs vsculpt-server

const name = process.argv[2];
let text = '';
process.stdin.setEncoding('utf8');
process.stdin.on('data', (d) => (text += d));
process.stdin.on('end', () => {
  let found = null;
  for (const line of text.split('\n')) {
    if (!line.startsWith('{')) continue;
    const m = JSON.parse(line);
    if (m.reason === 'compiler-artifact' && m.executable && m.target.name === name && m.target.kind.includes('bin') && !m.profile.test) {
      found = m.executable;
    }
  }
  if (!found) {
    console.error(`cargo reported no executable for the bin target "${name}": run \`cargo build -p ${name}\` to see why`);
    process.exit(1);
  }
  console.log(found);
});
