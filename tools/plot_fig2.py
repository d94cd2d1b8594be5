#!/usr/bin/python3
"""Draws the paper's Fig. 2 (joint angles, velocities and torques over time) from closed-loop logs.

Each log is a CSV with the header t,q0..q{n-1},v0..v{n-1},u0..u{n-1},residual,update_ms and
one row per control step. Several logs are overlaid (solid, dashed, dotted, ...) with the same
colour per joint, e.g. the FD and the ID controller on the same task:

    plot_fig2.py fd.csv id.csv --labels FD ID -o fig2.png [--residual]

--residual adds a fourth panel with the optimality residual on a log scale. The PNG is written
to a temporary file and renamed, so a reader never sees a half-written figure.
"""

import argparse
import math
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
from matplotlib.lines import Line2D  # noqa: E402

LINESTYLES = ["-", "--", ":", "-."]


from run_record import LogError, read_log, read_summary  # noqa: E402


def joint_colours(n):
    if n <= 10:
        cmap = plt.get_cmap("tab10")
        return [cmap(j) for j in range(n)]
    cmap = plt.get_cmap("viridis")
    return [cmap(j / (n - 1)) for j in range(n)]


def positive_or_nan(xs):
    """Values for a log-scale axis: non-positive and non-finite entries become gaps."""
    return [abs(x) if math.isfinite(x) and x != 0 else math.nan for x in xs]


def units(types, names=None):
    """Axis labels for joints of these kinds ("hinge", "slide"; None: hinges), naming the slides
    of a mixed model by `names` (else by index)."""
    slides = [j for j, kind in enumerate(types or []) if kind == "slide"]
    if not slides:
        return "joint angle [rad]", "joint velocity [rad/s]", "torque [N m]"
    if len(slides) == len(types):
        return "joint position [m]", "joint velocity [m/s]", "force [N]"
    which = ", ".join(names[j] if names and len(names) == len(types) else f"joint {j}" for j in slides)
    return (f"joint position [rad; m: {which}]", f"joint velocity [rad/s; m/s: {which}]",
            f"torque [N m; force in N: {which}]")


def joints_of(log_path):
    """The joints' names and kinds from the run summary beside a log (same path, .json), or
    (None, None)."""
    summary = os.path.splitext(log_path)[0] + ".json"
    if not os.path.exists(summary):
        return None, None
    try:
        s = read_summary(summary)
    except LogError:
        return None, None
    return s.get("joint_names"), s.get("joint_types")


def draw(logs, residual, title, names=None, types=None):
    n_max = max(log.n for log in logs)
    colours = joint_colours(n_max)
    q_label, v_label, u_label = units(types, names)
    panels = [("q", q_label), ("v", v_label), ("u", u_label)]
    if residual:
        panels.append(("residual", "optimality residual"))
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 2.4 * len(panels) + 0.8),
                             constrained_layout=True)
    for ax, (key, ylabel) in zip(axes, panels):
        for k, log in enumerate(logs):
            style = LINESTYLES[k % len(LINESTYLES)]
            if key == "residual":
                ax.semilogy(log.t, positive_or_nan(log.residual), style, color="0.2", lw=1.1)
                continue
            for j, series in enumerate(getattr(log, key)):
                ax.plot(log.t, series, style, color=colours[j], lw=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(True, which="major", alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[-1].set_xlim(min(log.t[0] for log in logs), max(log.t[-1] for log in logs))

    # legends: joints by colour on the top panel, logs by line style when several are overlaid
    if n_max <= 16:
        handles = [Line2D([], [], color=colours[j], lw=2) for j in range(n_max)]
        labels = names if names and len(names) == n_max else [f"joint {j}" for j in range(n_max)]
        axes[0].legend(handles, labels, loc="upper right",
                       ncol=min(n_max, 8), fontsize="small", framealpha=0.85)
    else:
        axes[0].set_title(f"colour: joint 0 (purple) to joint {n_max - 1} (yellow)",
                          fontsize="small", loc="right")
    if len(logs) > 1:
        handles = [Line2D([], [], color="0.2", ls=LINESTYLES[k % len(LINESTYLES)], lw=1.5)
                   for k in range(len(logs))]
        axes[1].legend(handles, [log.label for log in logs], loc="upper right",
                       fontsize="small", framealpha=0.85)
    if title:
        fig.suptitle(title)
    return fig


def save_atomically(fig, path, dpi):
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".plot_fig2_", suffix=".png", dir=directory)
    os.close(fd)
    try:
        fig.savefig(tmp, format="png", dpi=dpi)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Draws the paper's Fig. 2 from one or more closed-loop log CSVs.")
    parser.add_argument("logs", nargs="+", help="closed-loop log CSV files (overlaid)")
    parser.add_argument("--labels", nargs="+", help="legend label per log (default: file names)")
    parser.add_argument("-o", "--output", default="fig2.png", help="PNG to write (default fig2.png)")
    parser.add_argument("--residual", action="store_true",
                        help="add a panel with the optimality residual (log scale)")
    parser.add_argument("--title", help="figure title")
    parser.add_argument("--dpi", type=int, default=150, help="resolution (default 150)")
    args = parser.parse_args(argv)
    if args.labels is not None and len(args.labels) != len(args.logs):
        parser.error(f"--labels: expected {len(args.logs)} labels (one per log), "
                     f"got {len(args.labels)}")
    labels = args.labels or [os.path.splitext(os.path.basename(p))[0] for p in args.logs]
    try:
        logs = [read_log(path, label) for path, label in zip(args.logs, labels)]
    except LogError as err:
        print(f"plot_fig2.py: {err}", file=sys.stderr)
        return 1
    # the joints' names and kinds (units) from the first log's summary, when it has one
    fig = draw(logs, args.residual, args.title, *joints_of(args.logs[0]))
    try:
        save_atomically(fig, args.output, args.dpi)
    except OSError as err:
        print(f"plot_fig2.py: cannot write '{args.output}': {err.strerror or err}", file=sys.stderr)
        return 1
    finally:
        plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
