#!/usr/bin/env bash
# Runs every vsculpt test on a fresh machine: installs what the tests need
# (Chromium for the browser tests, the web client's npm packages), then
# formatting, lints, the Rust test suites and the browser end-to-end tests.
# Works wherever cargo puts its builds (CARGO_TARGET_DIR, build.target-dir in
# a cargo config, or the default target/): binaries are located by asking
# cargo, never by a fixed path.
set -euo pipefail
cd "$(dirname "$0")/.."

# --- what the tests need -------------------------------------------------
if ! command -v chromium >/dev/null 2>&1; then
  echo "== installing Chromium (Debian package) for the browser tests"
  if [ "$(id -u)" = 0 ]; then SUDO=""; else SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi
if [ -f web-client/package-lock.json ]; then
  echo "== installing the web client's packages (npm ci)"
  (cd web-client && npm ci --no-audit --no-fund --loglevel=error)
fi

# --- static checks -------------------------------------------------------
echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy -D warnings"
cargo clippy --workspace --all-targets --locked -- -D warnings

# --- Rust tests (kernel, protocol, server, bridge, end-to-end) -----------
echo "== cargo test"
cargo test --workspace --locked

# --- browser end-to-end tests (real headless Chromium) -------------------
if [ -f web-client/package.json ] && grep -q '"test"' web-client/package.json; then
  echo "== browser tests"
  # The debug server binary `cargo test` already built (dependencies are
  # optimised in the dev profile, so it solves at full speed), at the path
  # cargo reports for it: asking the same `cargo test` build again is free,
  # where `cargo build -p vsculpt-server` would rebuild the dependencies with
  # other features.
  server_bin=$(cargo test --workspace --locked --no-run --message-format=json-render-diagnostics |
    node scripts/cargo-executable.mjs vsculpt-server)
  (cd web-client && VSCULPT_SERVER_BIN="$server_bin" npm test)
fi
