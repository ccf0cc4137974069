#!/usr/bin/env bash
# The whole test suite, as the README gives it and CI runs it (after fmt and clippy):
#   1. the Rust workspace (cargo test --workspace);
#   2. the Python package: a venv in .venv with the pinned tools (python/requirements-dev.txt),
#      the extension built into it by maturin, then pytest python/tests (Ray tests included).
# Needs: a Rust toolchain and python3 (3.9+, with venv). The data is in tests/data/; the peer
# tests read $HAZE_PEERS_DIR or ../shared/peers and are skipped, with one line, without it.
set -euo pipefail
cd "$(dirname "$0")/.."

start=$(date +%s)
cargo test --workspace
rust_done=$(date +%s)

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r python/requirements-dev.txt
# maturin installs into the venv named by VIRTUAL_ENV. The extension is built as a wheel is, for
# any x86-64 (pyproject.toml's [tool.maturin] config; docs/performance.md §5.1), in a target
# directory of its own so that it and the native cargo builds do not rebuild each other's crates.
VIRTUAL_ENV="$PWD/.venv" CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}/portable" \
  .venv/bin/maturin develop --release --quiet
# The metrics test compares with the `haze` command that cargo test built.
export HAZE_BIN="${CARGO_TARGET_DIR:-$PWD/target}/debug/haze"
.venv/bin/python -m pytest python/tests
end=$(date +%s)
echo "test.sh: Rust $((rust_done - start)) s, Python (venv, build, pytest) $((end - rust_done)) s"
