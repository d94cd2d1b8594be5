#!/usr/bin/env bash
# The sanitizer job: builds everything with AddressSanitizer + UndefinedBehaviorSanitizer (clang,
# -O1 with line tables) into ${IDMPC_ASAN_BUILD_DIR:-build-asan} and runs the whole ctest suite.
# The first finding aborts its process (halt_on_error, abort_on_error), and every report of every
# process -- the idmpc commands the CLI tests start included, whose exit codes a test may expect
# to be non-zero anyway -- is also written to build-asan/sanitizer-logs; the job fails if any
# report is there. Suppressions cover third-party code only, each with its reason:
# tools/sanitizers/{asan,lsan,ubsan}.supp.
#
# clang rather than gcc: the instrumented build takes 7.5 min on 2 idle cores against about
# 14 min with gcc -O2, and runs the tests as fast. Cost, measured on 2 idle cores: the
# instrumented code runs 30-40x slower than the Release build (one C/GMRES full-horizon test:
# 0.74 s -> 30 s; UBSan is most of it: AddressSanitizer alone 5.4 s), so cgmres_test takes
# about 10 min and cli_test about 12 min; hence a per-test timeout of an hour.
#
# Debug checks are on (IDMPC_DEBUG_CHECKS=1: the call-order preconditions and their death tests).
#
#   tools/sanitize.sh            # build and run everything
#   tools/sanitize.sh --subset   # the subset CI runs (label `sanitize`, tests/CMakeLists.txt):
#                                # builds only its executables and idmpc
#   tools/sanitize.sh -R Cli     # extra arguments go to ctest
#   IDMPC_SANITIZE_TARGETS="idmpc cli_test" tools/sanitize.sh -R Cli
#                                # build only these targets (the executables the selected tests run)
#   tools/sanitize.sh --thread   # ThreadSanitizer instead, on the thread subset (label `threads`,
#                                # tests/CMakeLists.txt): the tests that run the library on several
#                                # threads at once; into ${IDMPC_TSAN_BUILD_DIR:-build-tsan}. Builds
#                                # only their executables (about 4 min on 2 idle cores).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=${IDMPC_JOBS:-$(nproc)}
supp=$here/tools/sanitizers

"$here/tools/setup.sh" clang
opt="-O1 -gline-tables-only -DNDEBUG -DIDMPC_DEBUG_CHECKS=1"
subset=0
thread=0
if [ "${1:-}" = "--subset" ]; then
  subset=1
  shift
elif [ "${1:-}" = "--thread" ]; then
  thread=1
  shift
fi
if [ "$thread" = 1 ]; then
  build=${IDMPC_TSAN_BUILD_DIR:-$here/build-tsan}
  sanitizers=thread
  flags="-fsanitize=thread -fno-omit-frame-pointer"
else
  build=${IDMPC_ASAN_BUILD_DIR:-$here/build-asan}
  sanitizers=address,undefined
  flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
fi
logs=$build/sanitizer-logs
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="$opt" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt" \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$sanitizers" \
  -DIDMPC_WERROR=ON -DIDMPC_BUILD_BENCH=OFF -DIDMPC_TEST_TIMEOUT=3600 \
  -DIDMPC_BUILD_PYTHON=OFF -DIDMPC_SANITIZE_SUBSET=ON ${IDMPC_CMAKE_ARGS:-} >/dev/null
# (the Python module is left out: an instrumented module needs the sanitizer runtime preloaded
# into the interpreter)
if [ "$thread" = 1 ]; then
  # the thread subset's executables only: none of them starts idmpc
  targets=$(cd "$build" && ctest -N -L threads | sed -n 's|^ *Test *#[0-9]*: \([a-z_]*_test\).*|\1|p' | sort -u)
  # shellcheck disable=SC2086  # a list of target names
  cmake --build "$build" -j "$jobs" --target $targets
  set -- -L threads "$@"
elif [ "$subset" = 1 ]; then
  # the subset's executables (a ctest is named <executable> or <executable>/<shard>) and idmpc
  targets=$(cd "$build" && ctest -N -L sanitize | sed -n 's|^ *Test *#[0-9]*: \([a-z_]*_test\).*|\1|p' | sort -u)
  # shellcheck disable=SC2086  # a list of target names
  cmake --build "$build" -j "$jobs" --target idmpc $targets
  set -- -L sanitize "$@"
elif [ -n "${IDMPC_SANITIZE_TARGETS:-}" ]; then
  # shellcheck disable=SC2086  # a list of target names
  cmake --build "$build" -j "$jobs" --target ${IDMPC_SANITIZE_TARGETS}
  set -- -LE partial "$@"
else
  set -- -LE partial "$@"
  cmake --build "$build" -j "$jobs"
fi

rm -rf "$logs"
mkdir -p "$logs"
common="halt_on_error=1:abort_on_error=1:print_summary=1:log_path=$logs/report"
export ASAN_OPTIONS="$common:detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:suppressions=$supp/asan.supp"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="$common:print_stacktrace=1:suppressions=$supp/ubsan.supp"
# history_size=7, the longest: a report needs the earlier access's stack, which a thread that
# has done much since has overwritten in a short history, and the race then goes unreported
export TSAN_OPTIONS="$common:history_size=7:second_deadlock_stack=1"

status=0
(cd "$build" && ctest --output-on-failure -j "$jobs" "$@") || status=$?
if compgen -G "$logs/report*" >/dev/null; then
  echo "sanitizer reports:" >&2
  for f in "$logs"/report*; do
    echo "==== $f" >&2
    cat "$f" >&2
  done
  status=1
fi
exit $status
