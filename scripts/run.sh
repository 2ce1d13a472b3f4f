#!/usr/bin/env bash
# Runs vsculpt on a fresh machine: installs the web client's packages from the
# npm registry (through the committed lockfile), then starts the server, which
# creates a demo design on first start and prints the URLs to open.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -f web-client/package-lock.json ] && [ ! -d web-client/node_modules ]; then
  (cd web-client && npm ci --no-audit --no-fund --loglevel=error)
fi
# Brotli/gzip copies of the vendored modules (npm ci's postinstall writes
# them; this catches a node_modules installed before that step existed).
(cd web-client && node tools/precompress.mjs)
exec cargo run --release --locked -p vsculpt-server -- "$@"
