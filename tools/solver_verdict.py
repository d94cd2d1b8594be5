#!/usr/bin/env -S /usr/bin/python3
"""The verdict per solver family: FD and ID under C/GMRES and under the Riccati solver, side by
side in one run, on the paper's swing-up (arm4 and the chains of Table 3) and the shipped arms'
reach and tracking tasks.

Usage: solver_verdict.py [--idmpc BUILD/src/idmpc] [--out docs/reference/solvers.md]
                         [--tasks paper_swingup panda_reach ...] [--chains chain8 ...]
                         [--duration S] [--chain-duration S] [--wp-duration S] [--quick]

Three parts, each a set of closed-loop `idmpc swingup` runs:
1. Per update: each (task, solver, formulation, derivatives) with the task's own settings: the
   median and mean update time, ID/FD per family (medians: the machine is shared), the final joint
   error or the tracking RMS, and deadline misses at the control rate. C/GMRES runs both
   derivative modes; the Riccati solver's stage Jacobians are matrices.
2. Work–precision: each family over its work per update (C/GMRES kmax, adjoint mode; Riccati SQP
   iterations), against its own optimality residual, the closed-loop cost and the distance to the
   converged solution: max over the run of |q(t) − q*(t)|, q* the closed loop of the same
   formulation under a converged controller (Riccati, 10 iterations per update). ID/FD at equal
   accuracy: the cheapest run of each formulation within a distance tolerance.
3. Under compute latency (`--latency measured`: each torque reaches the plant after the plant
   steps its update's wall time took): deadline misses and the outcome, per family.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

from report import cpu_model
from run_record import read_log

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_TASKS = ["paper_swingup", "panda_reach", "ur5e_reach", "iiwa14_reach", "panda_circle"]
DEFAULT_CHAINS = ["chain8", "chain16", "chain32"]
VARIANTS = [("cgmres", "matrix"), ("cgmres", "adjoint"), ("riccati", "matrix")]
# work–precision: the runs, each family's work per update, the converged reference
WP_RUNS = [("paper_swingup", None), ("paper_swingup", "chain8"), ("panda_reach", None)]
# every work–precision run over the fixed horizon T_f, solved in full at t = 0 (the Riccati
# solver's horizon, and the problem its converged reference solves; the paper's swing-up otherwise
# grows C/GMRES's horizon from zero, a different problem in its first seconds)
WP_FIXED_HORIZON = ("--alpha", "0", "--init-full-horizon", "true")
WP_KMAX = [1, 2, 3, 5, 10, 20]
WP_ITERATIONS = [1, 2, 3, 5]
REFERENCE_ITERATIONS = 10
DISTANCE_TOLERANCES = [1e-2, 1e-3]  # rad: "equal accuracy" = within this of the converged closed loop
LATENCY_TASKS = ["paper_swingup", "panda_reach"]


class Runner:
    def __init__(self, idmpc, workdir):
        self.idmpc, self.workdir, self.count = idmpc, workdir, 0

    def run(self, task, formulation, solver="cgmres", derivatives="adjoint", model=None, duration=0,
            kmax=None, iterations=None, latency=None, extra=()):
        """One closed loop; returns (summary, log path)."""
        self.count += 1
        base = os.path.join(self.workdir, f"run{self.count}")
        cmd = [self.idmpc, "swingup", "--task", os.path.join(ROOT, "mjcf", task + ".json"), "--solver", solver,
               "--formulation", formulation, "--derivatives", derivatives, "--summary", base + ".json",
               "--log", base + ".csv"]
        if model:
            cmd.append(os.path.join(ROOT, "mjcf", model + ".xml"))
        if duration:
            cmd += ["--duration", str(duration)]
        if kmax is not None:
            cmd += ["--kmax", str(kmax)]
        if iterations is not None:
            cmd += ["--iterations", str(iterations)]
        if latency:
            cmd += ["--latency", latency]
        cmd += list(extra)
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode not in (0, 2, 3):  # 2: diverged, 3: not reached; both are results
            sys.exit(f"solver_verdict: {' '.join(cmd)} failed (exit {done.returncode}): {done.stderr.strip()}")
        with open(base + ".json") as f:
            return json.load(f), base + ".csv"


def label(task, model):
    return f"{task} ({model})" if model else task


def outcome(s):
    if s["diverged"]:
        return f"diverged at {s['diverged_at']:.3g} s"
    if "tracking" in s:
        return f"RMS {1e3 * s['tracking']['position_rms']:.2f} mm"
    return f"{s['final_q_error']:.1e} rad"


def ratio(a, b):
    return a / b if b > 0 else float("nan")


def per_update(runner, tasks, chains, duration, chain_duration):
    runs = [(t, None, duration) for t in tasks] + [("paper_swingup", c, chain_duration) for c in chains]
    out = ["## Per update", "",
           "Each run with the task's own weights, horizon and limits (the chains: the paper's swing-up on the "
           f"chains of Table 3, {chain_duration:g} s). Update times in ms: median (mean); ID/FD of the medians. "
           "Outcome: the final max|q − q_ref| of a reach or swing-up, the position RMS of a tracking task.", "",
           "| task | solver | derivatives | FD ms | ID ms | ID/FD | FD outcome | ID outcome | deadline misses FD / ID |",
           "|---|---|---|---|---|---|---|---|---|"]
    for task, model, dur in runs:
        for solver, derivatives in VARIANTS:
            r = {f: runner.run(task, f, solver, derivatives, model, dur)[0] for f in ("fd", "id")}
            fd, id_ = r["fd"], r["id"]
            deriv = derivatives if solver == "cgmres" else "matrix (Jacobians)"
            out.append(f"| {label(task, model)} | {solver} | {deriv} | {fd['p50_update_ms']:.3f} "
                       f"({fd['mean_update_ms']:.3f}) | {id_['p50_update_ms']:.3f} ({id_['mean_update_ms']:.3f}) | "
                       f"**{ratio(id_['p50_update_ms'], fd['p50_update_ms']):.2f}** | {outcome(fd)} | {outcome(id_)} | "
                       f"{fd['latency']['deadline_misses']} / {id_['latency']['deadline_misses']} |")
            print(out[-1], file=sys.stderr)
    return out


def distance(log, reference):
    """max over the steps and the joints of |q − q*| [rad]; inf unless both ran every step."""
    a, b = read_log(log, "run"), read_log(reference, "reference")
    steps = len(a.t)
    if steps == 0 or len(b.t) != steps:
        return float("inf")
    return max(abs(a.q[j][k] - b.q[j][k]) for j in range(a.n) for k in range(steps))


def work_precision(runner, duration):
    out = ["## Work–precision", "",
           f"Each family over its work per update ({duration:g} s of each run, every run over the fixed horizon T_f "
           "solved in full at t = 0: `--alpha 0 --init-full-horizon true`): C/GMRES's kmax (adjoint mode) and the "
           "Riccati solver's SQP iterations per update. Each entry: median ms per update · mean optimality "
           "residual (each family's own: C/GMRES ‖F‖, Riccati the KKT residual; docs/solvers.md) · closed-loop "
           "cost ∫L dt · distance to the converged solution, max over the run of |q(t) − q*(t)| [rad], q* the closed "
           f"loop of the same formulation under a converged controller (Riccati, {REFERENCE_ITERATIONS} iterations "
           "per update). `*` diverged.", ""]
    verdict = ["| run | family | tolerance [rad] | cheapest FD | cheapest ID | ID/FD |",
               "|---|---|---|---|---|---|"]
    for task, model in WP_RUNS:
        out += [f"### {label(task, model)}", "", "| family | work | FD | ID |", "|---|---|---|---|"]
        refs = {f: runner.run(task, f, "riccati", "matrix", model, duration, iterations=REFERENCE_ITERATIONS,
                              extra=WP_FIXED_HORIZON) for f in ("fd", "id")}
        cheapest = {}
        for family, knob, values in (("cgmres", "kmax", WP_KMAX), ("riccati", "iterations", WP_ITERATIONS)):
            for k in values:
                cells = []
                for f in ("fd", "id"):
                    opts = {"kmax": k} if family == "cgmres" else {"iterations": k}
                    s, log = runner.run(task, f, family, "adjoint" if family == "cgmres" else "matrix", model,
                                        duration, extra=WP_FIXED_HORIZON, **opts)
                    d = float("inf") if s["diverged"] else distance(log, refs[f][1])
                    ms = s["p50_update_ms"]
                    cells.append(f"{ms:.3f} · {s['mean_residual']:.1e} · {s['closed_loop_cost']:.4g} · "
                                 f"{d:.1e}{' *' if s['diverged'] else ''}")
                    for tol in DISTANCE_TOLERANCES:
                        best = cheapest.get((family, f, tol))
                        if d <= tol and (best is None or ms < best[0]):
                            cheapest[(family, f, tol)] = (ms, f"{knob} {k}")
                out.append(f"| {family} | {knob} {k} | {cells[0]} | {cells[1]} |")
                print(out[-1], file=sys.stderr)
        ref_gap = distance(refs["fd"][1], refs["id"][1])
        out += ["", f"Converged references: cost FD {refs['fd'][0]['closed_loop_cost']:.4g}, ID "
                    f"{refs['id'][0]['closed_loop_cost']:.4g}; max|q_FD*(t) − q_ID*(t)| = {ref_gap:.1e} rad (the torque "
                    "rules differ: ID predicts the state over Δt, FD applies u_0).", ""]
        for family in ("cgmres", "riccati"):
            for tol in DISTANCE_TOLERANCES:
                fd, id_ = cheapest.get((family, "fd", tol)), cheapest.get((family, "id", tol))
                show = lambda c: f"{c[0]:.3f} ms ({c[1]})" if c else "none"
                r = f"**{ratio(id_[0], fd[0]):.2f}**" if fd and id_ else "—"
                verdict.append(f"| {label(task, model)} | {family} | {tol:g} | {show(fd)} | {show(id_)} | {r} |")
    return out + ["### At equal accuracy", "",
                  "The cheapest run (median ms per update) of each formulation whose closed loop stays within the "
                  "tolerance of the converged one (none: no run of the grid does):", ""] + verdict


def under_latency(runner, duration):
    out = ["## Under compute latency", "",
           "`--latency measured`: each torque reaches the plant after the whole plant steps its update's own wall "
           "time took (docs/formulations.md, Compute latency). C/GMRES in adjoint mode. Deadline misses: updates "
           "slower than the control period.", "",
           "| task | solver | FD misses / updates | ID misses / updates | FD outcome | ID outcome |",
           "|---|---|---|---|---|---|"]
    for task in LATENCY_TASKS:
        for solver, derivatives in (("cgmres", "adjoint"), ("riccati", "matrix")):
            r = {f: runner.run(task, f, solver, derivatives, None, duration, latency="measured")[0] for f in ("fd", "id")}
            cell = lambda s: f"{s['latency']['deadline_misses']} / {s['latency']['updates']}"
            out.append(f"| {task} | {solver} | {cell(r['fd'])} | {cell(r['id'])} | {outcome(r['fd'])} | "
                       f"{outcome(r['id'])} |")
            print(out[-1], file=sys.stderr)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--idmpc", default=os.path.join(ROOT, "build", "src", "idmpc"))
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "reference", "solvers.md"))
    p.add_argument("--tasks", nargs="+", default=DEFAULT_TASKS)
    p.add_argument("--chains", nargs="*", default=DEFAULT_CHAINS)
    p.add_argument("--duration", type=float, default=0, help="simulated seconds of each task (0: the task's own)")
    p.add_argument("--chain-duration", type=float, default=4, help="simulated seconds of the chains' swing-ups")
    p.add_argument("--wp-duration", type=float, default=2, help="simulated seconds of the work–precision runs")
    p.add_argument("--quick", action="store_true", help="short runs of every part (a check of the tool, not a result)")
    a = p.parse_args()
    if a.quick:
        a.duration, a.chain_duration, a.wp_duration = 0.05, 0.05, 0.05
    with tempfile.TemporaryDirectory() as work:
        runner = Runner(a.idmpc, work)
        parts = [per_update(runner, a.tasks, a.chains, a.duration, a.chain_duration),
                 work_precision(runner, a.wp_duration),
                 under_latency(runner, a.duration)]
    out = ["# The verdict per solver family", "",
           "FD and ID under C/GMRES and under the Riccati solver (Gauss–Newton SQP, one real-time iteration per "
           "update unless said otherwise), each closed loop against MuJoCo with the task's own weights, horizon and "
           "limits.", "",
           f"Machine: {cpu_model()}, {os.cpu_count()} cores, shared (compare ratios within a row, not absolute "
           "times). Regenerate: `tools/solver_verdict.py` (after `tools/build.sh`); "
           f"{runner.count} closed-loop runs.", ""]
    for part in parts:
        out += part + [""]
    with open(a.out, "w") as f:
        f.write("\n".join(out))
    print(f"wrote {a.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
