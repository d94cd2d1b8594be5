#!/usr/bin/env bash
# Builds idmpc in Release (tools/build.sh, benchmarks on), runs bench_dynamics and bench_solver
# with JSON output, then writes the tables and the scaling plot with tools/bench_tables.py.
#
# Usage: tools/bench.sh [OUT_DIR]            (default: results/bench)
# Environment: IDMPC_BUILD_DIR (build dir, default build-bench/, configured with
# -DIDMPC_NATIVE=ON: the benchmarks measure this machine), IDMPC_CMAKE_ARGS (extra CMake
# arguments), IDMPC_BENCH_ARGS (extra arguments for both binaries, e.g.
# "--benchmark_min_time=0.5", or "--benchmark_repetitions=3 --benchmark_report_aggregates_only=true"
# on a busy machine: the tables then use the medians; the binaries default to 0.2 s per case).
# Outputs: OUT_DIR/bench_dynamics.json, bench_solver.json, tables.md, scaling.png.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${IDMPC_BUILD_DIR:-$here/build-bench}
out=${1:-$here/results/bench}
read -r -a extra <<< "${IDMPC_BENCH_ARGS:-}"

"$here/tools/setup.sh"
IDMPC_BUILD_DIR="$build" \
  IDMPC_CMAKE_ARGS="-DIDMPC_NATIVE=ON -DIDMPC_BUILD_TESTS=OFF -DIDMPC_BUILD_RENDER=OFF ${IDMPC_CMAKE_ARGS:-} -DIDMPC_BUILD_BENCH=ON" \
  "$here/tools/build.sh"
mkdir -p "$out"

for layer in dynamics solver; do
  bin="$build/bench/bench_$layer"
  if [ ! -x "$bin" ]; then
    echo "bench.sh: $bin was not built" >&2
    exit 1
  fi
  echo "bench.sh: running bench_$layer" >&2
  # JSON goes to a temporary file, renamed once the run has finished
  "$bin" --benchmark_out="$out/bench_$layer.json.tmp" --benchmark_out_format=json "${extra[@]}"
  mv "$out/bench_$layer.json.tmp" "$out/bench_$layer.json"
done

/usr/bin/python3 "$here/tools/bench_tables.py" --dynamics "$out/bench_dynamics.json" \
  --solver "$out/bench_solver.json" --out-dir "$out" --build-dir "$build"
