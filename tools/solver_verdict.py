#!/usr/bin/env -S /usr/bin/python3
"""The verdict per solver family: FD and ID under C/GMRES and under the Riccati solver, side by
side in one run, on the paper's swing-up and the shipped arms' reach and tracking tasks.

Usage: solver_verdict.py [--idmpc BUILD/src/idmpc] [--out docs/reference/solvers.md]
                         [--tasks paper_swingup panda_reach ...] [--duration S]

Each (task, solver, formulation, derivatives) is one closed-loop `idmpc swingup` run; the table
gives the median and mean update time, ID/FD per family (medians: the machine is shared), the
final joint error or the tracking RMS, whether the target was reached, and deadline misses at
1 kHz. C/GMRES runs both derivative modes; the Riccati solver's stage Jacobians are matrices.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

from report import cpu_model

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_TASKS = ["paper_swingup", "panda_reach", "ur5e_reach", "iiwa14_reach", "panda_circle"]
VARIANTS = [("cgmres", "matrix"), ("cgmres", "adjoint"), ("riccati", "matrix")]


def run(idmpc, task, solver, formulation, derivatives, duration, workdir):
    summary = os.path.join(workdir, f"{task}_{solver}_{formulation}_{derivatives}.json")
    cmd = [idmpc, "swingup", "--task", os.path.join(ROOT, "mjcf", task + ".json"), "--solver", solver,
           "--formulation", formulation, "--derivatives", derivatives, "--summary", summary]
    if duration:
        cmd += ["--duration", str(duration)]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode not in (0, 2, 3):
        sys.exit(f"solver_verdict: {' '.join(cmd)} failed (exit {done.returncode}): {done.stderr.strip()}")
    with open(summary) as f:
        return json.load(f)


def outcome(s):
    if s["diverged"]:
        return f"diverged at {s['diverged_at']:.3g} s"
    if "tracking" in s:
        return f"RMS {1e3 * s['tracking']['position_rms']:.2f} mm"
    return f"{s['final_q_error']:.1e} rad"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--idmpc", default=os.path.join(ROOT, "build", "src", "idmpc"))
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "reference", "solvers.md"))
    p.add_argument("--tasks", nargs="+", default=DEFAULT_TASKS)
    p.add_argument("--duration", type=float, default=0, help="simulated seconds (0: the task's own)")
    a = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for task in a.tasks:
            for solver, derivatives in VARIANTS:
                r = {f: run(a.idmpc, task, solver, f, derivatives, a.duration, work) for f in ("fd", "id")}
                rows.append((task, solver, derivatives, r))
                print(f"{task} {solver} {derivatives}: FD {r['fd']['p50_update_ms']:.3f} ms, "
                      f"ID {r['id']['p50_update_ms']:.3f} ms", file=sys.stderr)
    out = ["# The verdict per solver family", "",
           "FD and ID under C/GMRES and under the Riccati solver (Gauss–Newton SQP, one real-time iteration "
           "per update), each closed loop against MuJoCo with the task's own weights, horizon and limits. "
           "Update times in ms: median (mean); ID/FD of the medians. Outcome: the final max|q − q_ref| of a "
           "reach, the position RMS of a tracking task.", "",
           f"Machine: {cpu_model()}, {os.cpu_count()} cores, shared (compare ratios within a row, not absolute "
           "times). Regenerate: `tools/solver_verdict.py` (after `tools/build.sh`).", "",
           "| task | solver | derivatives | FD ms | ID ms | ID/FD | FD outcome | ID outcome | deadline misses FD / ID |",
           "|---|---|---|---|---|---|---|---|---|"]
    for task, solver, derivatives, r in rows:
        fd, id_ = r["fd"], r["id"]
        ratio = id_["p50_update_ms"] / fd["p50_update_ms"] if fd["p50_update_ms"] > 0 else float("nan")
        deriv = derivatives if solver == "cgmres" else "matrix (Jacobians)"
        out.append(f"| {task} | {solver} | {deriv} | {fd['p50_update_ms']:.3f} ({fd['mean_update_ms']:.3f}) | "
                   f"{id_['p50_update_ms']:.3f} ({id_['mean_update_ms']:.3f}) | **{ratio:.2f}** | {outcome(fd)} | "
                   f"{outcome(id_)} | {fd['latency']['deadline_misses']} / {id_['latency']['deadline_misses']} |")
    with open(a.out, "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"wrote {a.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
