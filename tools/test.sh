#!/usr/bin/env bash
# The README's test command: installs dependencies, builds from scratch in Release, runs ctest.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/tools/setup.sh"
export IDMPC_BUILD_DIR=${IDMPC_BUILD_DIR:-$here/build}
IDMPC_CMAKE_ARGS="-DIDMPC_WERROR=ON ${IDMPC_CMAKE_ARGS:-}" "$here/tools/build.sh"
cd "$IDMPC_BUILD_DIR"
ctest --output-on-failure -j "$(nproc)"
