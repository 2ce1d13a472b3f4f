#!/usr/bin/env bash
# Builds the server (debug, or with the cargo flags given, e.g. --release) and
# prints the path of the executable as cargo reports it, so callers find the
# binary wherever cargo put it (CARGO_TARGET_DIR, build.target-dir, target/).
#   scripts/server-bin.sh            # debug build
#   scripts/server-bin.sh --release  # release build
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --locked -p vsculpt-server --bin vsculpt-server --message-format=json-render-diagnostics "$@" |
  node scripts/cargo-executable.mjs vsculpt-server
