#!/usr/bin/env bash
# Installs dependencies (as root), builds the release preset and runs the main job on the
# built-in data: `vkloc demo`. Extra arguments go to `vkloc demo` (e.g. --out DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$(id -u)" -eq 0 ]; then bash scripts/install-deps.sh; fi
cmake --preset release >/dev/null
cmake --build --preset release --target vkloc_cli
./build/release/vkloc demo "$@"
