#!/usr/bin/env -S /usr/bin/python3
"""Turns the Google Benchmark JSON of bench_dynamics and bench_solver into Markdown tables that
mirror the paper's Tables 1-3 (ours beside the paper's, as ratios), a dynamics-kernel table, the
performance-target check, and a log-scale PNG of per-update time against n and N.

All times are the benchmarks' CPU time per iteration (more robust than wall time to other
processes sharing the machine); the real (wall) time is in the JSON as well. With
--benchmark_repetitions the median aggregate of each case is used.

Usage: bench_tables.py --dynamics bench_dynamics.json --solver bench_solver.json \
           --out-dir results/bench [--build-dir build]
Writes <out-dir>/tables.md and <out-dir>/scaling.png (each through a temporary file + rename).
"""

import argparse
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile

import matplotlib

from run_record import load_paper_tables

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

CONTROLLERS = ["fd_matrix", "fd_adjoint", "id_matrix", "id_adjoint", "fd_matrix_scalar", "id_matrix_scalar",
               "id_adjoint_scalar"]
MODES = ["matrix", "adjoint"]
T3_N = [4, 8, 16, 24, 32]


def paper_tables():
    """The paper's Tables 1-3 (mjcf/paper_tables.json, the one copy, also read by idmpc)."""
    cells = load_paper_tables()
    t12 = [c for c in cells if c["table"] == "12"]
    n_ = sorted({c["N"] for c in t12})
    k_ = sorted({c["kmax"] for c in t12})

    def grid(f):
        by = {(c["kmax"], c["N"]): c for c in t12 if c["formulation"] == f}
        return ({k: [by[(k, N)]["ms"] for N in n_] for k in k_},
                {(k, N) for (k, N), c in by.items() if c["mark"]})

    fd, fd_marks = grid("fd")
    idd, id_marks = grid("id")
    t3 = {f: {c["n"]: c["ms"] for c in cells if c["table"] == "3" and c["formulation"] == f} for f in ("fd", "id")}
    return n_, k_, fd, idd, fd_marks, id_marks, t3


# paper (ms per update, matrix derivatives): '*' FD diverged, '+' ID needed Q_a = 1e-4
T12_N, T12_KMAX, PAPER_T1_FD, PAPER_T2_ID, PAPER_T1_DIVERGED, PAPER_T2_QA, PAPER_T3 = paper_tables()

# targets
T_ID_FD_RATIO = 0.6  # ID/FD per update, matrix mode, every n of Table 3
T_LINEAR_EXPONENT = 1.2  # adjoint per-update time ~ n^p with p at most this counts as linear
T_OVERHEAD = 1.3  # per update <= 1.3 x evals x N x one stage's work (ID adjoint, n=4, N=25, kmax=10)
T_ABS = {4: 0.13, 32: 1.6}  # ms, ID adjoint, N=25, kmax=10
T_RNEA_VS_MJ = 0.4
T_ABA_VS_MJ = 0.9
T_DERIV_VS_MJ = 1.5
T_TRIPLE_VS_RNEA = 3.0

UNIT_SECONDS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def load(path):
    with open(path) as f:
        doc = json.load(f)
    # one entry per case: the median aggregate when the run had repetitions, else the run itself
    iterations, medians = {}, {}
    for b in doc.get("benchmarks", []):
        name = b.get("run_name", b["name"])
        if b.get("run_type", "iteration") == "iteration":
            iterations.setdefault(name, dict(b, name=name))
        elif b.get("aggregate_name") == "median":
            medians[name] = dict(b, name=name)
    runs = [medians.get(name, b) for name, b in iterations.items()]
    runs += [b for name, b in medians.items() if name not in iterations]
    return doc.get("context", {}), runs


def seconds(b):
    """CPU time of one iteration [s]; None for an errored case."""
    if b.get("error_occurred"):
        return None
    return b["cpu_time"] * UNIT_SECONDS[b.get("time_unit", "ns")]


def parse_dynamics(runs):
    """{algorithm: {n: seconds}}"""
    out = {}
    for b in runs:
        m = re.match(r"^BM_(\w+)/(\w+)$", b["name"])
        if not m or seconds(b) is None or "_spatial" in m.group(2):  # tables: planar chains
            continue
        out.setdefault(m.group(1), {})[int(b["n"])] = seconds(b)
    return out


def parse_solver(runs):
    """updates {(ctrl, n, N, kmax): run}, residuals {(ctrl, n, N): run}, stage_ops {n: run}"""
    updates, residuals, stage_ops = {}, {}, {}
    for b in runs:
        name = b["name"]
        m = re.match(r"^BM_Update/(\w+)/n:(\d+)/N:(\d+)/kmax:(\d+)$", name)
        if m:
            updates[(m.group(1), int(m.group(2)), int(m.group(3)), int(m.group(4)))] = b
            continue
        m = re.match(r"^BM_Residual/(\w+)/n:(\d+)/N:(\d+)$", name)
        if m:
            residuals[(m.group(1), int(m.group(2)), int(m.group(3)))] = b
            continue
        m = re.match(r"^BM_StageVectorOps/n:(\d+)$", name)
        if m:
            stage_ops[int(m.group(1))] = b
    return updates, residuals, stage_ops


def ms(b):
    s = seconds(b) if b else None
    return None if s is None else 1e3 * s


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    decimals = max(0, digits - 1 - mag)
    return f"{x:.{decimals}f}"


def fmt_ratio(x):
    return "–" if x is None or not math.isfinite(x) else f"{x:.2f}"


def mark(b):
    """'*' when the recorded swing-up diverged (timed up to divergence), '+' when ID needed Q_a."""
    if not b:
        return ""
    s = ""
    if b.get("diverged", 0) > 0:
        s += "*"
    if b.get("Qa", 0) > 0:
        s += "+"
    return s


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def loglog_slope(points):
    """Least-squares exponent p of t ~ c n^p."""
    pts = [(math.log(n), math.log(t)) for n, t in points if t and t > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pts)
    return sxy / sxx if sxx > 0 else None


def verdict(ok):
    if ok is None:
        return "n/a"
    return "PASS" if ok else "MISS"


def machine_section(ctx_dyn, ctx_sol, build_dir):
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    ctx = ctx_sol or ctx_dyn
    compiler = ctx.get("compiler")
    if not compiler:
        try:
            compiler = subprocess.run(["c++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
        except (OSError, IndexError):
            compiler = "unknown"
    flags = {}
    if build_dir:
        try:
            with open(os.path.join(build_dir, "CMakeCache.txt")) as f:
                for line in f:
                    m = re.match(r"^(CMAKE_BUILD_TYPE|CMAKE_CXX_FLAGS|CMAKE_CXX_FLAGS_RELEASE|IDMPC_NATIVE|"
                                 r"CMAKE_CXX_COMPILER):\w+=(.*)$", line.strip())
                    if m:
                        flags[m.group(1)] = m.group(2)
        except OSError:
            pass
    build = flags.get("CMAKE_BUILD_TYPE", ctx.get("idmpc_build_type", "unknown"))
    cxxflags = " ".join(x for x in [flags.get("CMAKE_CXX_FLAGS", ""), flags.get("CMAKE_CXX_FLAGS_RELEASE", "")] if x)
    cxxflags += " -O3 (target options)"
    if flags.get("IDMPC_NATIVE", "OFF").upper() in ("ON", "1", "TRUE", "YES"):
        cxxflags += " -march=native"
    rows = [
        ("CPU", f"{cpu} ({ctx.get('mhz_per_cpu', '?')} MHz reported)"),
        ("cores", f"{ctx.get('num_cpus', os.cpu_count())} (os.cpu_count() = {os.cpu_count()})"),
        ("compiler", f"{compiler} ({flags.get('CMAKE_CXX_COMPILER', 'c++')})"),
        ("build", f"{build}; flags: {cxxflags.strip()}; SIMD: {ctx.get('idmpc_simd', '?')}"),
        ("Google Benchmark library", f"built as {ctx.get('library_build_type', '?')} (Debian package; does not affect our code)"),
        ("load average at start", "dynamics " + ", ".join(fmt(x, 2) for x in ctx_dyn.get("load_avg", []))
         + "; solver " + ", ".join(fmt(x, 2) for x in ctx_sol.get("load_avg", []))),
        ("date", ctx.get("date", "?")),
        ("host", f"{ctx.get('host_name', '?')}, {platform.system()} {platform.release()}"),
        ("timing", "CPU time per iteration (benchmark `cpu_time`), single thread"),
    ]
    return "## Machine\n\n" + table(["", ""], rows) + "\n"


def tables_12(updates):
    out = ["## Tables 1–2: 4-link arm (arm4), ms per update, ours (paper)\n",
           "Ours: C/GMRES update replayed on the first 0.3 s of a closed-loop swing-up. "
           "`*` our recorded swing-up diverged within its record (timed up to divergence); "
           "`+` ID needed Q_a = 1e-4. Paper: `*` FD diverged (10 s run), `+` ID needed Q_a = 1e-4. "
           "Paper figures are matrix-mode (Pinocchio, Core i5 2.0 GHz); compare ratios, not absolutes. "
           "Our matrix mode runs its stage derivatives in SIMD lanes (the default); Table 3 has it "
           "stage by stage too, the paper's arithmetic. "
           "The paper's FD N=10, kmax=10 entry 8.1 is as printed (likely 0.81).\n"]
    for mode in MODES:
        out.append(f"### Derivatives: {mode}\n")
        for title, f, paper, pmarks in (("Table 1 — FD", "fd", PAPER_T1_FD, PAPER_T1_DIVERGED),
                                        ("Table 2 — ID", "id", PAPER_T2_ID, PAPER_T2_QA)):
            pm = "*" if f == "fd" else "+"
            rows = []
            for kmax in T12_KMAX:
                row = [f"kmax={kmax}"]
                for j, N in enumerate(T12_N):
                    b = updates.get((f"{f}_{mode}", 4, N, kmax))
                    p = paper[kmax][j]
                    row.append(f"{fmt(ms(b))}{mark(b)} ({p}{pm if (kmax, N) in pmarks else ''})")
                rows.append(row)
            out.append(f"**{title}, {mode}** (ms per update)\n")
            out.append(table(["", *[f"N={N}" for N in T12_N]], rows) + "\n")
        rows = []
        for kmax in T12_KMAX:
            row = [f"kmax={kmax}"]
            for j, N in enumerate(T12_N):
                fd = ms(updates.get((f"fd_{mode}", 4, N, kmax)))
                idt = ms(updates.get((f"id_{mode}", 4, N, kmax)))
                r = idt / fd if fd and idt else None
                pr = PAPER_T2_ID[kmax][j] / PAPER_T1_FD[kmax][j]
                note = "‡" if (kmax, N) == (10, 10) else ""
                row.append(f"{fmt_ratio(r)} ({fmt_ratio(pr)}{note})")
            rows.append(row)
        out.append(f"**Ratio ID/FD, {mode}** (paper's ratio; ‡ uses the printed 8.1)\n")
        out.append(table(["", *[f"N={N}" for N in T12_N]], rows) + "\n")
    return "\n".join(out)


def table_3(updates):
    rows = []
    for n in T3_N:
        get = {c: updates.get((c, n, 25, 10)) for c in CONTROLLERS}
        t = {c: ms(b) for c, b in get.items()}

        def ratio(a, b):
            return t[a] / t[b] if t[a] and t[b] else None

        pf, pi = PAPER_T3["fd"].get(n), PAPER_T3["id"].get(n)
        rows.append([
            n,
            f"{fmt(t['fd_matrix'])}{mark(get['fd_matrix'])}", f"{fmt(t['id_matrix'])}{mark(get['id_matrix'])}",
            fmt_ratio(ratio("id_matrix", "fd_matrix")),
            f"{fmt(t['fd_matrix_scalar'])}", f"{fmt(t['id_matrix_scalar'])}",
            fmt_ratio(ratio("id_matrix_scalar", "fd_matrix_scalar")),
            f"{fmt(t['fd_adjoint'])}{mark(get['fd_adjoint'])}", f"{fmt(t['id_adjoint'])}{mark(get['id_adjoint'])}",
            fmt_ratio(ratio("id_adjoint", "fd_adjoint")),
            fmt_ratio(ratio("fd_adjoint", "fd_matrix")), fmt_ratio(ratio("id_adjoint", "id_matrix")),
            fmt(pf, 2) if pf else "–", fmt(pi, 2) if pi else "–", fmt_ratio(pi / pf) if pf else "–",
        ])
    hdr = ["n", "FD matrix", "ID matrix", "ID/FD matrix", "FD matrix, no lanes", "ID matrix, no lanes",
           "ID/FD matrix, no lanes", "FD adjoint", "ID adjoint", "ID/FD adjoint",
           "FD adj/mat", "ID adj/mat", "paper FD", "paper ID", "paper ID/FD"]
    return ("## Table 3: chains, N = 25, kmax = 10, ms per update\n\n"
            "`*`/`+` as above. Paper figures: matrix mode, their machine. Matrix mode runs its "
            "stage derivatives in SIMD lanes (FD after the rollout, ID with the stage dynamics); "
            "\"no lanes\" is the same controller stage by stage, the paper's arithmetic.\n\n" + table(hdr, rows) + "\n")


SHOOTINGS = [("single", ""), ("multiple", "_multiple")]
BASE_CONTROLLERS = ["fd_matrix", "fd_adjoint", "id_matrix", "id_adjoint"]


def best(updates, f, suffix, key):
    """Fastest of formulation f's variants (matrix/adjoint, SIMD stages on) under one shooting scheme
    whose recorded swing-up did not diverge: (ms, variant) or (None, None)."""
    found = (None, None)
    for mode in MODES:
        b = updates.get((f"{f}_{mode}{suffix}", *key))
        t = ms(b)
        if t is None or b.get("diverged", 0) > 0:
            continue
        if found[0] is None or t < found[0]:
            found = (t, mode)
    return found


def shooting_tables(updates):
    """Single vs multiple shooting per variant, and each formulation's best variant side by side."""
    if not any(k[0].endswith("_multiple") for k in updates):
        return ""
    out = ["## Single vs multiple shooting (docs/multiple_shooting.md), and best with best\n",
           "Multiple shooting: states and costates as unknowns, condensed so that GMRES runs on the inputs "
           "(one F evaluation more per update). `*`/`+` as above. *Best*: the fastest of a formulation's "
           "variants (matrix or adjoint derivatives) whose recorded swing-up did not diverge.\n"]
    ns = sorted({k[1] for k in updates if k[0].endswith("_multiple") and k[2] == 25 and k[3] == 10})
    rows = []
    for n in ns:
        key = (n, 25, 10)
        row = [n]
        for c in BASE_CONTROLLERS:
            for _, suffix in SHOOTINGS:
                b = updates.get((c + suffix, *key))
                row.append(f"{fmt(ms(b))}{mark(b)}")
        bests = {}
        for name, suffix in SHOOTINGS:
            for f in ("fd", "id"):
                bests[(f, name)] = best(updates, f, suffix, key)
        for name, _ in SHOOTINGS:
            fd, idt = bests[("fd", name)][0], bests[("id", name)][0]
            row.append(fmt_ratio(idt / fd) if fd and idt else "–")
        overall = {f: min((bests[(f, nm)] for nm, _ in SHOOTINGS if bests[(f, nm)][0] is not None),
                          default=(None, None)) for f in ("fd", "id")}
        fd, idt = overall["fd"][0], overall["id"][0]
        row.append(fmt_ratio(idt / fd) if fd and idt else "–")
        rows.append(row)
    hdr = ["n"] + [f"{c} {name}" for c in BASE_CONTROLLERS for name, _ in SHOOTINGS] + \
          ["best ID/best FD single", "best ID/best FD multiple", "best ID/best FD overall"]
    out.append("### Chains, N = 25, kmax = 10, ms per update\n")
    out.append(table(hdr, rows) + "\n")
    rows = []
    for kmax in T12_KMAX:
        row = [f"kmax={kmax}"]
        for N in T12_N:
            key = (4, N, kmax)
            cells = []
            for name, suffix in SHOOTINGS:
                fd, idt = best(updates, "fd", suffix, key)[0], best(updates, "id", suffix, key)[0]
                cells.append(fmt_ratio(idt / fd) if fd and idt else "–")
            row.append(" / ".join(cells))
        rows.append(row)
    out.append("### arm4 (Tables 1–2 grid): best ID / best FD, single / multiple shooting\n")
    out.append(table(["", *[f"N={N}" for N in T12_N]], rows) + "\n")
    return "\n".join(out)


def scaling_tables(updates, residuals):
    ns = sorted({k[1] for k in updates if k[2] == 25 and k[3] == 10})
    rows = []
    for n in ns:
        row = [n]
        for c in CONTROLLERS:
            b = updates.get((c, n, 25, 10))
            row.append(f"{fmt(ms(b))}{mark(b)}")
        for c in CONTROLLERS:
            b = updates.get((c, n, 25, 10))
            row.append(fmt(b.get("us_per_eval")) if b and not b.get("error_occurred") else "–")
        b = updates.get(("id_adjoint", n, 25, 10))
        row.append(fmt(b.get("evals"), 3) if b else "–")
        rows.append(row)
    hdr = ["n", *[f"{c} ms" for c in CONTROLLERS], *[f"{c} µs/F" for c in CONTROLLERS], "F evals/update"]
    out = ["## Scaling in n (N = 25, kmax = 10)\n",
           "Per update [ms] and per F evaluation [µs] (update time / F evaluations).\n",
           table(hdr, rows) + "\n"]
    exps = []
    for c in CONTROLLERS:
        pts = [(n, ms(updates.get((c, n, 25, 10)))) for n in ns if n >= 8]
        pts_all = [(n, ms(updates.get((c, n, 25, 10)))) for n in ns]
        exps.append([c, fmt(loglog_slope(pts), 3), fmt(loglog_slope(pts_all), 3)])
    out.append("Fitted exponent p of time ∝ n^p (least squares on log-log):\n")
    out.append(table(["controller", "p (n ≥ 8)", "p (all n)"], exps) + "\n")

    for n in (4, 16):
        Ns = sorted({k[2] for k in updates if k[1] == n and k[3] == 10})
        rows = []
        for N in Ns:
            row = [N]
            for c in CONTROLLERS:
                b = updates.get((c, n, N, 10))
                row.append(f"{fmt(ms(b))}{mark(b)}")
            rows.append(row)
        out.append(f"## Scaling in N (n = {n}, kmax = 10), ms per update\n")
        out.append(table(["N", *CONTROLLERS], rows) + "\n")
    if residuals:
        rows = []
        for n in ns:
            row = [n] + [fmt(1e6 * seconds(residuals[(c, n, 25)])) if (c, n, 25) in residuals
                         and seconds(residuals[(c, n, 25)]) else "–" for c in CONTROLLERS]
            rows.append(row)
        out.append("## One F evaluation alone (BM_Residual, N = 25), µs\n")
        out.append(table(["n", *CONTROLLERS], rows) + "\n")
    return "\n".join(out)


DYN_COLS = [("Rnea", "RNEA"), ("MjInverse", "mj_inverse"), ("Aba", "ABA"), ("MjForward", "mj_forward"),
            ("Crba", "CRBA"), ("RneaDerivatives", "RNEA derivs"), ("AbaDerivatives", "ABA derivs"),
            ("RneaVjp", "RNEA + vjp"), ("RneaVjpSweepOnly", "vjp sweep"), ("Minv", "dense M⁻¹"),
            ("MinvApply", "M⁻¹x"), ("LtdlSolve", "LᵀDL solve"), ("MjSolveM", "mj_solveM"),
            ("LtdlFactorSolve", "LᵀDL factor + solve"), ("MjFactorSolveM", "mj_factorM + mj_solveM")]

# the MuJoCo-relative levels Pinocchio 3.7 reached on this machine (the upper end of its range
# over n = 4…32, measured side by side with MuJoCo 2.2): kernel, MuJoCo baseline, level
PINOCCHIO_LEVELS = (("Crba", "MjInverse", 0.38, "CRBA"), ("AbaDerivatives", "MjForward", 2.3, "ABA derivatives"),
                    ("Minv", "MjForward", 0.73, "dense M⁻¹ from q"),
                    ("LtdlSolve", "MjSolveM", 1.25, "M⁻¹x with a factor of M (LᵀDL solve)"))


def dyn_ratio(dyn, a, b, n):
    x, y = dyn.get(a, {}).get(n), dyn.get(b, {}).get(n)
    return x / y if x and y else None


def dynamics_tables(dyn):
    ns = sorted({n for d in dyn.values() for n in d})
    rows = [[n] + [fmt(1e6 * dyn[k][n]) if n in dyn.get(k, {}) else "–" for k, _ in DYN_COLS] for n in ns]
    out = ["## Dynamics kernels, µs per call\n",
           "One call at a random fixed state; MuJoCo with constraints and actuation disabled, same inputs. "
           "`RNEA + vjp` is the adjoint triple (∂ID/∂q)ᵀw, (∂ID/∂v)ᵀw, M w including the RNEA pass it needs; "
           "`vjp sweep` the reverse sweep alone; `M⁻¹x` after one ABA (`minv_apply`, what FD adjoint uses); "
           "`LᵀDL solve` with the sparse factor of M computed beforehand (as `mj_solveM` and Pinocchio's "
           "`cholesky::solve`), `LᵀDL factor + solve` with M given (as `mj_factorM` + `mj_solveM`).\n",
           table(["n", *[c for _, c in DYN_COLS]], rows) + "\n"]
    rrows = []
    for n in ns:
        rrows.append([n,
                      fmt_ratio(dyn_ratio(dyn, "Rnea", "MjInverse", n)),
                      fmt_ratio(dyn_ratio(dyn, "Aba", "MjForward", n)),
                      fmt_ratio(dyn_ratio(dyn, "RneaDerivatives", "MjInverse", n)),
                      fmt_ratio(dyn_ratio(dyn, "RneaVjp", "Rnea", n)),
                      fmt_ratio(dyn_ratio(dyn, "AbaDerivatives", "MjForward", n)),
                      fmt_ratio(dyn_ratio(dyn, "Crba", "Rnea", n)),
                      fmt_ratio(dyn_ratio(dyn, "Crba", "MjInverse", n)),
                      fmt_ratio(dyn_ratio(dyn, "Minv", "MjForward", n)),
                      fmt_ratio(dyn_ratio(dyn, "MinvApply", "MjSolveM", n)),
                      fmt_ratio(dyn_ratio(dyn, "MinvApply", "MjFactorSolveM", n)),
                      fmt_ratio(dyn_ratio(dyn, "LtdlSolve", "MjSolveM", n)),
                      fmt_ratio(dyn_ratio(dyn, "LtdlFactorSolve", "MjFactorSolveM", n))])
    out.append("Ratios:\n")
    out.append(table(["n", "RNEA / mj_inverse", "ABA / mj_forward", "RNEA derivs / mj_inverse",
                      "(RNEA + vjp) / RNEA", "ABA derivs / mj_forward", "CRBA / RNEA", "CRBA / mj_inverse",
                      "dense M⁻¹ / mj_forward", "M⁻¹x / mj_solveM", "M⁻¹x / (mj_factorM + mj_solveM)",
                      "LᵀDL solve / mj_solveM", "LᵀDL factor + solve / (mj_factorM + mj_solveM)"], rrows) + "\n")
    srows = [[n, fmt(1e6 * dyn["FdStageAba"][n]), fmt(1e6 * dyn["FdStageCrbaLtdl"][n]),
              fmt_ratio(dyn_ratio(dyn, "FdStageCrbaLtdl", "FdStageAba", n))]
             for n in ns if n in dyn.get("FdStageAba", {}) and n in dyn.get("FdStageCrbaLtdl", {})]
    if srows:
        out.append("FD-adjoint stage, forward work (q̈ = FD(q, v, τ), one M⁻¹x, the RNEA pass at (q, v, q̈) "
                   "its adjoint needs), µs: through ABA (what FD adjoint does: `aba`, `minv_apply`, "
                   "`rnea_after_aba`) and through M (bias RNEA, CRBA, LᵀDL factor, two solves, RNEA):\n")
        out.append(table(["n", "through ABA", "through M", "M / ABA"], srows) + "\n")
    exps = [[c, fmt(loglog_slope([(n, dyn.get(k, {}).get(n)) for n in ns if n >= 8]), 3)] for k, c in DYN_COLS]
    out.append("Fitted exponent p of time ∝ n^p (n ≥ 8):\n")
    out.append(table(["kernel", "p"], exps) + "\n")
    return "\n".join(out)


def targets_section(dyn, updates, stage_ops):
    rows = []

    # ID/FD in matrix mode at every n of Table 3
    vals, oks = [], []
    for n in (8, 16, 24, 32):
        fd, idt = ms(updates.get(("fd_matrix", n, 25, 10))), ms(updates.get(("id_matrix", n, 25, 10)))
        r = idt / fd if fd and idt else None
        vals.append(f"n={n}: {fmt_ratio(r)}")
        oks.append(None if r is None else r <= T_ID_FD_RATIO)
    all_ok = None if any(o is None for o in oks) else all(oks)
    rows.append([f"ID/FD per update ≤ {T_ID_FD_RATIO} at every n of Table 3 (matrix, N=25, kmax=10)",
                 "; ".join(vals), verdict(all_ok)])

    # adjoint beats matrix at every n >= 8
    ns = sorted({k[1] for k in updates if k[2] == 25 and k[3] == 10 and k[1] >= 8})
    for f in ("fd", "id"):
        vals, oks = [], []
        for n in ns:
            a, m = ms(updates.get((f"{f}_adjoint", n, 25, 10))), ms(updates.get((f"{f}_matrix", n, 25, 10)))
            r = a / m if a and m else None
            vals.append(f"n={n}: {fmt_ratio(r)}")
            oks.append(None if r is None else r < 1)
        all_ok = None if not oks or any(o is None for o in oks) else all(oks)
        rows.append([f"{f.upper()}: adjoint beats matrix at every n ≥ 8 (adjoint/matrix < 1)",
                     "; ".join(vals), verdict(all_ok)])

    # adjoint grows linearly in n
    for f in ("fd", "id"):
        p = loglog_slope([(n, ms(updates.get((f"{f}_adjoint", n, 25, 10)))) for n in ns])
        rows.append([f"{f.upper()} adjoint grows linearly in n (log-log exponent over n ≥ 8 ≤ {T_LINEAR_EXPONENT})",
                     f"p = {fmt(p, 3)} (n = {ns[0] if ns else '?'}…{ns[-1] if ns else '?'})",
                     verdict(None if p is None else p <= T_LINEAR_EXPONENT)])

    # solver overhead, ID adjoint n=4 N=25 kmax=10
    b = updates.get(("id_adjoint", 4, 25, 10))
    triple = dyn.get("RneaVjp", {}).get(4)
    vec = stage_ops.get(4)
    if b and not b.get("error_occurred") and triple and vec:
        vec_s = seconds(vec) / vec.get("N", 25)
        stage = triple + vec_s
        evals = b.get("evals", 13)
        bound = evals * 25 * stage
        upd = seconds(b)
        ratio = upd / bound
        rows.append([f"solver overhead: per update ≤ {T_OVERHEAD} × evals × N × stage work (ID adjoint, n=4, N=25, kmax=10)",
                     f"update {fmt(1e3 * upd)} ms; evals {fmt(evals, 3)} × N 25 × stage {fmt(1e6 * stage)} µs "
                     f"(RNEA+vjp {fmt(1e6 * triple)} + vector ops {fmt(1e6 * vec_s)}) = {fmt(1e3 * bound)} ms; "
                     f"ratio {fmt(ratio, 3)}", verdict(ratio <= T_OVERHEAD)])
    else:
        rows.append(["solver overhead (ID adjoint, n=4, N=25, kmax=10)", "missing data", "n/a"])

    # absolute times
    for n, limit in T_ABS.items():
        t = ms(updates.get(("id_adjoint", n, 25, 10)))
        rows.append([f"ID adjoint n={n}, N=25, kmax=10 < {limit} ms", f"{fmt(t)} ms",
                     verdict(None if t is None else t < limit)])

    # dynamics kernels
    dn = sorted(dyn.get("Rnea", {}))
    for (a, b_, limit, text) in (("Rnea", "MjInverse", T_RNEA_VS_MJ, "RNEA ≤ {} × mj_inverse at every n"),
                                 ("Aba", "MjForward", T_ABA_VS_MJ, "ABA ≤ {} × mj_forward at every n"),
                                 ("RneaDerivatives", "MjInverse", T_DERIV_VS_MJ,
                                  "full RNEA derivatives ≤ {} × mj_inverse at every n"),
                                 ("RneaVjp", "Rnea", T_TRIPLE_VS_RNEA, "adjoint triple (RNEA + vjp) ≤ {} × RNEA at every n")):
        rs = [(n, dyn_ratio(dyn, a, b_, n)) for n in dn]
        ok = None if not rs or any(r is None for _, r in rs) else all(r <= limit for _, r in rs)
        worst = max((r for _, r in rs if r is not None), default=None)
        rows.append([text.format(limit), "; ".join(f"n={n}: {fmt_ratio(r)}" for n, r in rs) + f" (worst {fmt_ratio(worst)})",
                     verdict(ok)])
    # Pinocchio's MuJoCo-relative levels, at n = 4…32 (the range they were measured over)
    for (a, b_, limit, what) in PINOCCHIO_LEVELS:
        rs = [(n, dyn_ratio(dyn, a, b_, n)) for n in dn if 4 <= n <= 32]
        ok = None if not rs or any(r is None for _, r in rs) else all(r <= limit for _, r in rs)
        base = {"MjInverse": "mj_inverse", "MjForward": "mj_forward", "MjSolveM": "mj_solveM"}[b_]
        rows.append([f"{what} ≤ {limit} × {base} at n = 4…32 (Pinocchio's level)",
                     "; ".join(f"n={n}: {fmt_ratio(r)}" for n, r in rs), verdict(ok)])
    return "## Target check\n\n" + table(["target", "measured", "verdict"], rows) + "\n"


def integer_ticks(ax, values):
    """Log x axis labelled with the measured values themselves."""
    if values:
        ax.set_xticks(values)
        ax.set_xticklabels([str(v) for v in values])
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def plot(updates, path):
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    styles = {"fd_matrix": ("tab:red", "o", "-"), "fd_adjoint": ("tab:orange", "s", "-"),
              "id_matrix": ("tab:blue", "o", "-"), "id_adjoint": ("tab:green", "s", "-"),
              "fd_matrix_scalar": ("tab:pink", "v", ":"), "id_matrix_scalar": ("tab:cyan", "v", ":"),
              "id_adjoint_scalar": ("tab:olive", "^", ":")}
    ns_all = []
    for c in CONTROLLERS:
        pts = sorted((k[1], ms(b)) for k, b in updates.items()
                     if k[0] == c and k[2] == 25 and k[3] == 10 and ms(b) is not None)
        if not pts:
            continue
        ns_all += [p[0] for p in pts]
        color, marker, ls = styles[c]
        ax1.plot([p[0] for p in pts], [p[1] for p in pts], color=color, marker=marker, ls=ls,
                 label=c.replace("_", " "))
        div = [(n, t) for n, t in pts if updates[(c, n, 25, 10)].get("diverged", 0) > 0]
        if div:
            ax1.scatter([p[0] for p in div], [p[1] for p in div], s=120, facecolors="none",
                        edgecolors="k", zorder=5)
    for f, color in (("fd", "tab:red"), ("id", "tab:blue")):
        pts = sorted(PAPER_T3[f].items())
        ax1.plot([p[0] for p in pts], [p[1] for p in pts], color=color, marker="x", ls=":", alpha=0.6,
                 label=f"paper {f.upper()} (matrix, their machine)")
    if ns_all:
        ref = [x for x in sorted(set(ns_all))]
        t_ref = ms(updates.get(("id_adjoint", ref[0], 25, 10)))
        if t_ref:
            ax1.plot(ref, [t_ref * n / ref[0] for n in ref], color="gray", ls="--", lw=0.8, label="∝ n")
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    integer_ticks(ax1, sorted(set(ns_all)))
    ax1.set_xlabel("n (joints)")
    ax1.set_ylabel("ms per C/GMRES update")
    ax1.set_title("per update vs n (N = 25, kmax = 10)")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)

    for n, ls in ((4, "--"), (16, "-")):
        for c in CONTROLLERS:
            pts = sorted((k[2], ms(b)) for k, b in updates.items()
                         if k[0] == c and k[1] == n and k[3] == 10 and ms(b) is not None)
            if not pts:
                continue
            color, marker, _ = styles[c]
            ax2.plot([p[0] for p in pts], [p[1] for p in pts], color=color, marker=marker, ls=ls,
                     label=f"{c.replace('_', ' ')}, n={n}")
            div = [(N, t) for N, t in pts if updates[(c, n, N, 10)].get("diverged", 0) > 0]
            if div:
                ax2.scatter([p[0] for p in div], [p[1] for p in div], s=120, facecolors="none",
                            edgecolors="k", zorder=5)
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    integer_ticks(ax2, sorted({k[2] for k in updates if k[3] == 10 and k[1] in (4, 16)}))
    ax2.set_xlabel("N (horizon steps)")
    ax2.set_ylabel("ms per C/GMRES update")
    ax2.set_title("per update vs N (kmax = 10; dashed n = 4, solid n = 16)")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, ncol=2)
    fig.suptitle("idmpc C/GMRES per-update CPU time (circled: swing-up diverged, timed up to divergence)",
                 fontsize=10)
    fig.tight_layout()
    fd, tmp = tempfile.mkstemp(suffix=".png", dir=os.path.dirname(path) or ".")
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=120, format="png")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    plt.close(fig)


def write_atomic(path, text):
    fd, tmp = tempfile.mkstemp(suffix=".md", dir=os.path.dirname(path) or ".")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dynamics", required=True, help="bench_dynamics JSON")
    ap.add_argument("--solver", required=True, help="bench_solver JSON")
    ap.add_argument("--out-dir", default="results/bench")
    ap.add_argument("--build-dir", default=None, help="CMake build dir (for the build flags)")
    args = ap.parse_args()

    try:
        ctx_dyn, runs_dyn = load(args.dynamics)
        ctx_sol, runs_sol = load(args.solver)
    except (OSError, ValueError) as e:
        sys.exit(f"bench_tables.py: cannot read benchmark JSON: {e}")
    dyn = parse_dynamics(runs_dyn)
    updates, residuals, stage_ops = parse_solver(runs_sol)
    if not dyn or not updates:
        sys.exit("bench_tables.py: no dynamics or no BM_Update results in the JSON files")
    errors = [b["name"] + ": " + b.get("error_message", "") for b in runs_dyn + runs_sol if b.get("error_occurred")]

    os.makedirs(args.out_dir, exist_ok=True)
    parts = ["# idmpc benchmarks\n",
             "Generated by tools/bench_tables.py from bench_dynamics and bench_solver (Google Benchmark JSON). "
             "Per-update times: one C/GMRES update (kmax + 3 F evaluations) replayed on the recorded states of "
             "a closed-loop swing-up with the same controller, warm-started exactly as in the loop.\n",
             machine_section(ctx_dyn, ctx_sol, args.build_dir),
             targets_section(dyn, updates, stage_ops),
             tables_12(updates),
             table_3(updates),
             shooting_tables(updates),
             scaling_tables(updates, residuals),
             dynamics_tables(dyn)]
    if errors:
        parts.append("## Cases that reported an error\n\n" + "\n".join(f"- {e}" for e in errors) + "\n")
    write_atomic(os.path.join(args.out_dir, "tables.md"), "\n".join(parts))
    plot(updates, os.path.join(args.out_dir, "scaling.png"))
    print(f"wrote {os.path.join(args.out_dir, 'tables.md')} and {os.path.join(args.out_dir, 'scaling.png')}")


if __name__ == "__main__":
    main()
