#!/usr/bin/env bash
# The README's main command: installs dependencies, builds idmpc (Release, -march=native), runs
# the paper's swing-up (4-link arm, N = 25, kmax = 10, 10 s) with both formulations and both
# derivative modes, and under the Riccati solver, and the under-actuated cart-pole's swing-up, then
# writes into results/: logs, summaries, the Fig. 2 plots (C/GMRES, Riccati, cart-pole), the
# FD-vs-ID video and a short report.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
results=${IDMPC_RESULTS:-$here/results}
"$here/tools/setup.sh"
export IDMPC_BUILD_DIR=${IDMPC_RUN_BUILD_DIR:-$here/build-release}
IDMPC_CMAKE_ARGS="-DIDMPC_NATIVE=ON -DIDMPC_BUILD_TESTS=OFF -DIDMPC_BUILD_BENCH=OFF -DIDMPC_BUILD_PYTHON=OFF" "$here/tools/build.sh"
idmpc="$IDMPC_BUILD_DIR/src/idmpc"
mkdir -p "$results"
model="$here/mjcf/arm4.xml"

echo "== model check"
"$idmpc" check "$model" --samples 10

# matrix mode twice: stage by stage (--no-simd-stages, the paper's arithmetic) and with its stage
# derivatives in SIMD lanes (the default); adjoint mode with its default lanes
for v in matrix_paper matrix adjoint; do
  d=${v%_paper}
  lanes=()
  [ "$v" = matrix_paper ] && lanes=(--no-simd-stages)
  for f in fd id; do
    echo "== swing-up: C/GMRES (${f^^}), $d derivatives${lanes:+, stage by stage}"
    "$idmpc" swingup "$model" --formulation "$f" --derivatives "$d" "${lanes[@]}" \
      --log "$results/swingup_${f}_${v}.csv" --summary "$results/swingup_${f}_${v}.json"
  done
done

# the same swing-up under the other solver family: Gauss-Newton SQP with a Riccati recursion, one
# iteration per update (docs/solvers.md)
for f in fd id; do
  echo "== swing-up: Riccati SQP-RTI (${f^^})"
  "$idmpc" swingup "$model" --solver riccati --formulation "$f" \
    --log "$results/swingup_${f}_riccati.csv" --summary "$results/swingup_${f}_riccati.json"
done

# an under-actuated model: the cart-pole, its pole passive, swung up by the cart's force alone
for f in fd id; do
  echo "== cart-pole swing-up: C/GMRES (${f^^})"
  "$idmpc" swingup --task "$here/mjcf/cartpole_swingup.json" --formulation "$f" \
    --log "$results/cartpole_${f}.csv" --summary "$results/cartpole_${f}.json"
done

# and the acrobot, its shoulder passive, swung up by the elbow under the Riccati solver
for f in fd id; do
  echo "== acrobot swing-up: Riccati SQP-RTI (${f^^})"
  "$idmpc" swingup --task "$here/mjcf/acrobot_swingup.json" --formulation "$f" \
    --log "$results/acrobot_${f}.csv" --summary "$results/acrobot_${f}.json"
done

echo "== Fig. 2"
/usr/bin/python3 "$here/tools/plot_fig2.py" "$results/swingup_fd_matrix_paper.csv" "$results/swingup_id_matrix_paper.csv" \
  --labels "C/GMRES (FD)" "C/GMRES (ID)" --residual -o "$results/fig2.png"

/usr/bin/python3 "$here/tools/plot_fig2.py" "$results/swingup_fd_riccati.csv" "$results/swingup_id_riccati.csv" \
  --labels "Riccati (FD)" "Riccati (ID)" --residual -o "$results/fig2_riccati.png"

/usr/bin/python3 "$here/tools/plot_fig2.py" "$results/cartpole_fd.csv" "$results/cartpole_id.csv" \
  --labels "C/GMRES (FD)" "C/GMRES (ID)" --residual --title "Cart-pole swing-up (the pole passive)" \
  -o "$results/fig2_cartpole.png"

/usr/bin/python3 "$here/tools/plot_fig2.py" "$results/acrobot_fd.csv" "$results/acrobot_id.csv" \
  --labels "Riccati (FD)" "Riccati (ID)" --residual --title "Acrobot swing-up (the shoulder passive)" \
  -o "$results/fig2_acrobot.png"

echo "== video"
"$idmpc" render "$model" --compare "$results/swingup_fd_matrix_paper.csv" "$results/swingup_id_matrix_paper.csv" \
  --out "$results/swingup_fd_vs_id.mp4"

echo "== report"
/usr/bin/python3 "$here/tools/report.py" "$results"
echo
echo "results in $results: report.md, fig2.png, fig2_riccati.png, fig2_cartpole.png, fig2_acrobot.png, swingup_fd_vs_id.mp4, swingup_*.csv, swingup_*.json, cartpole_*, acrobot_*"
