#!/usr/bin/env bash
# The README's test command: installs dependencies, builds in Release with warnings as errors,
# runs the fast tier of the tests (ctest -LE acceptance, the Python module's pytest included),
# then installs to a temporary prefix and uses the install from outside the sources.
#
#   tools/test.sh                 # the fast tier and the install checks
#   tools/test.sh --acceptance    # the acceptance tier only (ctest -L acceptance: the long
#                                 # closed-loop runs), in the same build directory, built if needed
#
# Extra arguments after the mode go to ctest (e.g. -R tracking).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tier=fast
if [ "${1:-}" = "--acceptance" ]; then
  tier=acceptance
  shift
fi
export IDMPC_BUILD_DIR=${IDMPC_BUILD_DIR:-$here/build}
if [ "$tier" = acceptance ]; then
  # reuses the build the fast tier made (an incremental build: nothing to do when it is current)
  IDMPC_CMAKE_ARGS="-DIDMPC_WERROR=ON ${IDMPC_CMAKE_ARGS:-}" "$here/tools/build.sh"
  cd "$IDMPC_BUILD_DIR"
  started=$SECONDS
  ctest --output-on-failure -j "$(nproc)" -L acceptance "$@"
  echo "idmpc test: the acceptance tier passed in $((SECONDS - started)) s"
  exit 0
fi
"$here/tools/setup.sh"
IDMPC_CMAKE_ARGS="-DIDMPC_WERROR=ON ${IDMPC_CMAKE_ARGS:-}" "$here/tools/build.sh"
cd "$IDMPC_BUILD_DIR"
build=$(pwd)
started=$SECONDS
ctest --output-on-failure -j "$(nproc)" -LE acceptance "$@"
echo "idmpc test: the fast tier passed in $((SECONDS - started)) s"

# the install: no source or build path inside, find_package(idmpc) from a program of its own
# (examples/cpp), and the installed idmpc finding its data from any directory
started=$SECONDS
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
prefix=$stage/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
leaks=()
while IFS= read -r -d '' f; do
  if strings -a "$f" | grep -qF -e "$here" -e "$build"; then leaks+=("$f"); fi
done < <(find "$prefix" -type f -print0)
if [ ${#leaks[@]} -gt 0 ]; then
  echo "idmpc test: installed files hold the source or build path: ${leaks[*]}" >&2
  exit 1
fi
# the core component alone loads Eigen and nothing else
mkdir "$stage/core"
cat > "$stage/core/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(core_only LANGUAGES CXX)
find_package(idmpc CONFIG REQUIRED COMPONENTS core)
if(NOT TARGET idmpc::core OR TARGET idmpc::experiment OR TARGET mujoco::mujoco OR TARGET nlohmann_json::nlohmann_json)
  message(FATAL_ERROR "COMPONENTS core: expected idmpc::core and none of experiment, mujoco, nlohmann_json")
endif()
CMAKE
cmake -S "$stage/core" -B "$stage/core/build" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake -S "$here/examples/cpp" -B "$stage/example" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$stage/example" -j "$(nproc)"
cd "$stage"
# a program of its own finds no data beside itself: one line saying how to set it
if env -u IDMPC_DATA_DIR "$stage/example/closed_loop" 2>"$stage/err"; then
  echo "idmpc test: the example ran without a data directory" >&2
  exit 1
fi
grep -q "IDMPC_DATA_DIR is not set" "$stage/err" || { cat "$stage/err" >&2; exit 1; }
IDMPC_DATA_DIR=$prefix/share/idmpc "$stage/example/closed_loop"
# a task file of the user's own needs no data directory: an installed reach task, by path
env -u IDMPC_DATA_DIR "$stage/example/closed_loop" "$prefix/share/idmpc/mjcf/lite6_reach.json" 200
# the formulation and the solver chosen on its command line
env -u IDMPC_DATA_DIR "$stage/example/closed_loop" "$prefix/share/idmpc/mjcf/lite6_reach.json" 200 fd cgmres \
  | grep -q "^cgmres (fd) on "
# an under-actuated task: the cart-pole, its pole passive
env -u IDMPC_DATA_DIR "$stage/example/closed_loop" "$prefix/share/idmpc/mjcf/cartpole_swingup.json" 300 id \
  | grep -q "^cgmres (id) on "
# the installed command: 0 (reached) or 2 (not reached in 0.2 s) completed the run
status=0
env -u IDMPC_DATA_DIR "$prefix/bin/idmpc" swingup --duration 0.2 || status=$?
if [ "$status" -ne 0 ] && [ "$status" -ne 2 ]; then
  echo "idmpc test: the installed 'idmpc swingup' failed (exit $status)" >&2
  exit 1
fi

# the installed Python module, from outside the sources: it finds the installed data itself, and
# the example's own loop and the library's give the same run
python_dir=$(find "$prefix" -name 'idmpc*.so' -printf '%h\n' | head -n 1)
[ -n "$python_dir" ] || { echo "idmpc test: the Python module was not installed" >&2; exit 1; }
env -u IDMPC_DATA_DIR PYTHONPATH="$python_dir" /usr/bin/python3 "$here/examples/python/closed_loop.py" | tee "$stage/py.out"
grep -q "^Python loop: " "$stage/py.out"
echo "idmpc test: install, consumer, installed idmpc and Python module passed in $((SECONDS - started)) s"
cd "$here"
