#!/usr/bin/env bash
# Configures and builds idmpc in Release into ${IDMPC_BUILD_DIR:-build}.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${IDMPC_BUILD_DIR:-$here/build}
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release ${IDMPC_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j "$(nproc)"
