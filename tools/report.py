#!/usr/bin/env -S /usr/bin/python3
"""Writes the main job's Markdown report from the swing-up summaries and logs.

Usage: report.py RESULTS_DIR  (reads swingup_{fd,id}_{matrix_paper,matrix,adjoint,riccati}.{json,csv},
cartpole_{fd,id}.json, acrobot_{fd,id}.json;
writes report.md)
"""
import json
import math
import os
import platform
import subprocess
import sys

from run_record import load_paper_tables, read_log, read_summary


def torque_agreement(log_a, log_b, skip_s=0.0):
    """RMS over time of |u_a − u_b| relative to the RMS of |u_b|, from skip_s on."""
    a, b = read_log(log_a, "a"), read_log(log_b, "b")
    num = den = 0.0
    for k, t in enumerate(a.t[:len(b.t)]):
        if t < skip_s:
            continue
        num += sum((a.u[j][k] - b.u[j][k]) ** 2 for j in range(a.n))
        den += sum(b.u[j][k] ** 2 for j in range(b.n))
    return math.sqrt(num / den) if den > 0 else float("nan")


def max_angle_difference(log_a, log_b):
    a, b = read_log(log_a, "a"), read_log(log_b, "b")
    return max(abs(a.q[j][k] - b.q[j][k]) for j in range(a.n) for k in range(min(len(a.t), len(b.t))))


def write_lines(path, lines):
    """Writes the lines to path whole or not at all (a temporary beside it, then renamed)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)
    print("wrote " + path)


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def compiler():
    try:
        return subprocess.run(["c++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "unknown compiler"


# the variants of tools/run.sh: file suffix and how the report names it
VARIANTS = (("matrix_paper", "matrix, stage by stage (the paper's arithmetic)"),
            ("matrix", "matrix, stage derivatives in SIMD lanes"),
            ("adjoint", "adjoint (ID: stages in SIMD lanes; FD: none under single shooting)"))


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: report.py RESULTS_DIR")
    out_dir = sys.argv[1]
    def summary(name):
        path = os.path.join(out_dir, name + ".json")
        if not os.path.exists(path):
            sys.exit(f"report.py: missing summary '{path}'")
        return read_summary(path)

    runs = {(f, d): summary(f"swingup_{f}_{d}") for f in ("fd", "id") for d, _ in VARIANTS}
    riccati = {f: summary(f"swingup_{f}_riccati") for f in ("fd", "id")}
    cartpole = {f: summary(f"cartpole_{f}") for f in ("fd", "id")}
    acrobot = {f: summary(f"acrobot_{f}") for f in ("fd", "id")}
    lines = ["# idmpc: the paper's swing-up (4-link arm, N = 25, kmax = 10, 10 s)", ""]
    lines += [f"Machine: {cpu_model()}, {os.cpu_count()} cores; {compiler()}; Release build "
              "(`-O3`, `-march=native` for this job).", ""]
    lines += ["| controller | derivatives | diverged | mean ms/update | p50 | p95 | F evals | "
              "final max abs(q - q_ref) [rad] | final norm(v) [rad/s] | mean residual |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for (f, d), s in runs.items():
        div = f"yes, at {s['diverged_at']:.3f} s" if s["diverged"] else "no"
        lines.append(f"| C/GMRES ({f.upper()}) | {dict(VARIANTS)[d]} | {div} | {s['mean_update_ms']:.3f} | "
                     f"{s['p50_update_ms']:.3f} | {s['p95_update_ms']:.3f} | {s['evaluations_per_update']} | "
                     f"{s['final_q_error']:.2e} | {s['final_v_norm']:.2e} | {s['mean_residual']:.2e} |")
    for f, s in riccati.items():
        div = f"yes, at {s['diverged_at']:.3f} s" if s["diverged"] else "no"
        lines.append(f"| Riccati SQP-RTI ({f.upper()}) | matrix (stage Jacobians) | {div} | {s['mean_update_ms']:.3f} | "
                     f"{s['p50_update_ms']:.3f} | {s['p95_update_ms']:.3f} | {s['evaluations_per_update']} | "
                     f"{s['final_q_error']:.2e} | {s['final_v_norm']:.2e} | {s['mean_residual']:.2e} (KKT) |")
    paper = {c["formulation"]: c["ms"] for c in load_paper_tables()
             if c["table"] == "12" and c["N"] == 25 and c["kmax"] == 10}
    lines += ["", "Ratio ID/FD of the mean (p50) time per update, measured side by side in this run:", ""]
    for d, name in VARIANTS:
        fd, idd = runs[("fd", d)], runs[("id", d)]
        lines.append(f"- {name}: {idd['mean_update_ms'] / fd['mean_update_ms']:.2f} "
                     f"({idd['p50_update_ms'] / fd['p50_update_ms']:.2f}); the paper (N = 25, kmax = 10): "
                     f"{paper['id']}/{paper['fd']} = {paper['id'] / paper['fd']:.2f}")
    fd, idd = riccati["fd"], riccati["id"]
    lines.append(f"- Riccati SQP-RTI (one Gauss–Newton iteration per update, the horizon fixed at T_f): "
                 f"{idd['mean_update_ms'] / fd['mean_update_ms']:.2f} "
                 f"({idd['p50_update_ms'] / fd['p50_update_ms']:.2f}): there both formulations pay the same stage "
                 "Jacobians and recursion, and ID saves only the ABA derivatives and the dense dynamics products "
                 "(docs/solvers.md)")
    # the under-actuated swing-ups: ID/FD per update and each formulation's outcome
    for pair, what, figure in ((cartpole, "cart-pole swing-up (mjcf/cartpole_swingup.json, C/GMRES, kmax = %d)"
                                % cartpole["fd"]["task"]["cgmres"]["kmax"], "fig2_cartpole.png"),
                               (acrobot, "acrobot swing-up (mjcf/acrobot_swingup.json, Riccati SQP-RTI)",
                                "fig2_acrobot.png")):
        fd, idd = pair["fd"], pair["id"]
        outcome = {f: ("diverged at %.3f s" % s["diverged_at"] if s["diverged"] else
                       ("reached" if s["reached"] else "not reached") + " (final %.1e)" % s["final_q_error"])
                   for f, s in pair.items()}
        lines.append(f"- Under-actuated {what}: ID/FD {idd['mean_update_ms'] / fd['mean_update_ms']:.2f} "
                     f"({idd['p50_update_ms'] / fd['p50_update_ms']:.2f}); FD {outcome['fd']}, ID {outcome['id']}; "
                     f"`{figure}`")
    lines += ["", "Same control from both formulations (Q_a = 0): relative RMS difference of the torque "
              "histories, RMS of |u_ID − u_FD| over RMS of |u_FD|:", ""]
    for d, name in VARIANTS:
        a = os.path.join(out_dir, f"swingup_id_{d}.csv")
        b = os.path.join(out_dir, f"swingup_fd_{d}.csv")
        lines.append(f"- {name}: whole run {torque_agreement(a, b):.3f}, after the first 0.5 s "
                     f"{torque_agreement(a, b, 0.5):.4f}; largest joint-angle difference "
                     f"{max_angle_difference(a, b):.3g} rad")
    lines += ["", "Outputs: `fig2.png` (the paper's Fig. 2, FD and ID overlaid; `fig2_riccati.png` the same "
              "under the Riccati solver), "
              "`swingup_fd_vs_id.mp4` (both arms overlaid), the logs `swingup_*.csv` and summaries "
              "`swingup_*.json`.", ""]
    tmp = os.path.join(out_dir, ".report.md.tmp")
    with open(tmp, "w") as fh:
        fh.write("\n".join(lines))
    os.replace(tmp, os.path.join(out_dir, "report.md"))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
