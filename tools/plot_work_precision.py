#!/usr/bin/python3
"""Work-precision plot of `idmpc sweep --tables work-precision` (work_precision.csv): for each run,
time per update against the mean optimality residual (top) and against the closed-loop cost
(bottom), one line per formulation, derivative mode and kind of products through its kmax values.
A formulation wins where its curve lies below and left of the other's.

Usage: /usr/bin/python3 tools/plot_work_precision.py work_precision.csv OUT.png
"""
import csv
import math
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_work_precision.py work_precision.csv OUT.png")
    source, out = sys.argv[1], sys.argv[2]
    try:
        rows = [r for r in read(source) if r["table"] == "work-precision"]
    except (OSError, KeyError) as e:
        sys.exit(f"plot_work_precision.py: cannot read '{source}' as a work-precision table: {e}")
    if not rows:
        sys.exit(f"plot_work_precision.py: '{source}' holds no work-precision cell")
    runs = list(dict.fromkeys(r["model"] for r in rows))
    fig, axes = plt.subplots(2, len(runs), figsize=(3.6 * len(runs), 6.4), squeeze=False)
    colour = {"fd": "tab:red", "id": "tab:blue"}
    style = {("matrix", "difference"): "-", ("matrix", "exact"): ":", ("adjoint", "difference"): "--",
             ("adjoint", "exact"): "-."}
    for col, run in enumerate(runs):
        mine = [r for r in rows if r["model"] == run]
        n = mine[0]["n"]
        for key in dict.fromkeys((r["formulation"], r["derivatives"], r["products"]) for r in mine):
            f, d, p = key
            line = sorted((r for r in mine if (r["formulation"], r["derivatives"], r["products"]) == key),
                          key=lambda r: int(r["kmax"]))
            for row, field in ((0, "mean_residual"), (1, "closed_loop_cost")):
                ax = axes[row][col]
                ok = [r for r in line if r["diverged"] == "0" and math.isfinite(float(r[field]))]
                ax.plot([float(r["mean_update_ms"]) for r in ok], [float(r[field]) for r in ok],
                        style.get((d, p), "-"), marker="o", ms=3, color=colour[f],
                        label=f"{f.upper()} {d}, {p}")
                bad = [r for r in line if r["diverged"] == "1"]
                ax.plot([float(r["mean_update_ms"]) for r in bad], [float(r[field]) for r in bad], "x",
                        color=colour[f], ms=5)
        for row in (0, 1):
            ax = axes[row][col]
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", lw=0.3)
            ax.set_xlabel("mean ms per update")
        axes[0][col].set_title(f"{run} (n = {n})", fontsize=9)
        axes[0][col].set_ylabel("mean residual ‖F‖")
        axes[1][col].set_ylabel("closed-loop cost ∫L dt")
    axes[0][0].legend(fontsize=6, loc="best")
    fig.suptitle("work-precision: each line through kmax = "
                 + ", ".join(dict.fromkeys(r["kmax"] for r in rows)) + "; x: diverged", fontsize=9)
    fig.tight_layout()
    # written beside OUT and renamed: an interrupted plot leaves no half-written file
    directory = os.path.dirname(os.path.abspath(out))
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(out) + ".", suffix=".png", dir=directory)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110)
        os.chmod(tmp, 0o644)
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    print(f"written: {out}")


if __name__ == "__main__":
    main()
