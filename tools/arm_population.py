#!/usr/bin/env -S /usr/bin/python3
"""Generated arms against the defaults: how often a task of only the model, a start and a joint
target reaches, under FD and ID, on arms nobody tuned anything for.

Usage: arm_population.py [--arms K] [--seed S] [--idmpc BUILD/src/idmpc] [--jobs J]
                         [--solver auto|cgmres|riccati] [--task reach|circle]
                         [--out docs/reference/arm_population.md] [--keep DIR]

Each arm is a fixed-base serial chain written here as MJCF, drawn at random (seeded):
- 2–7 hinges: the first about the vertical, the next alternately about the two horizontal axes
  (some arms planar: every hinge about one horizontal axis), a wrist roll about the link on arms of
  6 and 7 (the 5-dof arms have none);
- links 0.1–0.45 m, their masses 0.5–2 times a scale drawn log-uniformly from 0.2–20 kg, inertia
  of a uniform rod; no contacts;
- armature (half the arms) log-uniform 0.002–0.5 times the scale, damping (two thirds) log-uniform
  0.02–5 times the scale;
- actuators, one kind per arm: torque motors with a ctrlrange of 1.5–4 times the largest holding
  torque over the workspace, position servos with that forcerange, or position servos without
  one (kp for 3–30 rad/s at the link's own inertia);
- gravity compensation (a third of the arms, drawn from a generator of its own so that the rest of
  each arm is as without it): MuJoCo >= 2.3's body gravcomp, 1 on every link or 0.3–1 on some;
- a start within ±1 rad per joint (a third of the arms start stretched, every horizontal hinge at 0:
  a singular configuration) and a joint target 0.3–1 rad away per joint.
The task file holds only the model, q0 and qref; every other setting is the default
(docs/tasks.md). Reached: max|q − q_ref| < 5e-3 rad at the end of the default 6 s, without
divergence; the plant never receives more than the actuator range (its clamp), and the table
counts the runs where the horizon's torques left the range.

--task circle: the same arms, the task the arm's tip site ("tip", at the end of the last link)
following a circle of 5 cm radius at 0.5 Hz from q0 (qref "q0"; the circle's plane, direction and
orientation weight the defaults'); reached: the RMS position error over the last half of the 6 s
run (from the log's x, y, z against x_ref, y_ref, z_ref) below 5 mm, without divergence.
"""
import argparse
import concurrent.futures
import json
import math
import os
import random
import subprocess
import tempfile

from report import cpu_model, write_lines

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
G = 9.81


def fmt(x):
    text = "%.6g" % x
    return "0" if text == "-0" else text


def draw_arm(rng, index):
    """One arm's parameters (a dict) from the seeded generator."""
    n = [2, 3, 4, 5, 6, 7][index % 6]
    planar = n <= 4 and rng.random() < 0.4
    axes = []
    for k in range(n):
        if planar:
            axes.append("0 1 0")
        elif k == 0:
            axes.append("0 0 1")
        elif n >= 6 and k == n - 2:
            axes.append("0 0 1")  # wrist roll about the (vertical at q = 0) link
        else:
            axes.append("0 1 0" if k % 2 == 1 else "1 0 0")
    scale = math.exp(rng.uniform(math.log(0.2), math.log(20.0)))
    lengths = [rng.uniform(0.1, 0.45) for _ in range(n)]
    masses = [scale * rng.uniform(0.5, 2.0) * (0.8 ** k) for k in range(n)]
    armature = [scale * math.exp(rng.uniform(math.log(0.002), math.log(0.5))) for _ in range(n)] \
        if rng.random() < 0.5 else [0.0] * n
    damping = [scale * math.exp(rng.uniform(math.log(0.02), math.log(5.0))) for _ in range(n)] \
        if rng.random() < 2 / 3 else [0.0] * n
    kind = rng.choice(["motor", "servo", "servo_no_forcerange"])
    # the largest holding torque of joint k: every link beyond it stretched horizontally
    hold = []
    for k in range(n):
        torque, reach = 0.0, 0.0
        for j in range(k, n):
            torque += masses[j] * G * (reach + 0.5 * lengths[j])
            reach += lengths[j]
        hold.append(max(torque, 0.05 * scale))
    margin = [rng.uniform(1.5, 4.0) for _ in range(n)]
    omega = [3.0 * 10 ** rng.uniform(0.0, 1.0) for _ in range(n)]  # servo bandwidth [rad/s]
    stretched = rng.random() < 1 / 3
    q0 = [0.0 if stretched and axes[k] != "0 0 1" else rng.uniform(-1.0, 1.0) for k in range(n)]
    qref = [q0[k] + rng.choice([-1, 1]) * rng.uniform(0.3, 1.0) for k in range(n)]
    return {"n": n, "planar": planar, "axes": axes, "scale": scale, "lengths": lengths, "masses": masses,
            "armature": armature, "damping": damping, "kind": kind, "hold": hold, "margin": margin, "omega": omega,
            "stretched": stretched, "q0": q0, "qref": qref}


def draw_gravcomp(rng, arm):
    """Per-link gravcomp: none (two thirds), 1 on every link, or 0.3–1 on about half the links."""
    n = arm["n"]
    u = rng.random()
    if u < 2 / 3:
        arm["gravcomp"] = [0.0] * n
    elif u < 5 / 6:
        arm["gravcomp"] = [1.0] * n
    else:
        arm["gravcomp"] = [rng.uniform(0.3, 1.0) if rng.random() < 0.5 else 0.0 for _ in range(n)]
        if not any(arm["gravcomp"]):
            arm["gravcomp"][-1] = 0.5


def gravcomp_kind(arm):
    gc = arm.get("gravcomp", [])
    return "none" if not any(gc) else ("full" if all(x == 1.0 for x in gc) else "partial")


def mjcf(arm, name):
    n = arm["n"]
    lines = ['<mujoco model="%s">' % name, '  <option timestep="0.001"/>',
             '  <default><geom contype="0" conaffinity="0"/></default>', "  <worldbody>"]
    indent = "    "
    pos = "0 0 0.2"
    for k in range(n):
        L, m = arm["lengths"][k], arm["masses"][k]
        I_perp, I_ax = m * L * L / 12 + m * 1e-4, m * 1e-4
        gravcomp = arm.get("gravcomp", [0.0] * n)[k]
        lines.append('%s<body name="link%d" pos="%s"%s>' %
                     (indent, k, pos, ' gravcomp="%s"' % fmt(gravcomp) if gravcomp else ""))
        lines.append('%s  <joint name="joint%d" axis="%s" armature="%s" damping="%s"/>' %
                     (indent, k, arm["axes"][k], fmt(arm["armature"][k]), fmt(arm["damping"][k])))
        lines.append('%s  <inertial pos="0 0 %s" mass="%s" diaginertia="%s %s %s"/>' %
                     (indent, fmt(L / 2), fmt(m), fmt(I_perp), fmt(I_perp), fmt(I_ax)))
        lines.append('%s  <geom type="capsule" fromto="0 0 0 0 0 %s" size="%s" mass="0"/>' %
                     (indent, fmt(L), fmt(0.02 + 0.01 * math.log10(1 + arm["scale"]))))
        indent += "  "
        pos = "0 0 %s" % fmt(L)
    lines.append('%s<site name="tip" pos="%s"/>' % (indent, pos))
    for k in reversed(range(n)):
        indent = indent[:-2]
        lines.append("%s</body>" % indent)
    lines.append("  </worldbody>")
    lines.append("  <actuator>")
    for k in range(n):
        limit = arm["margin"][k] * arm["hold"][k]
        if arm["kind"] == "motor":
            lines.append('    <motor joint="joint%d" ctrllimited="true" ctrlrange="%s %s"/>' %
                         (k, fmt(-limit), fmt(limit)))
        else:
            # kp for a natural frequency of 3–30 rad/s at the joint's own link inertia
            inertia = sum(arm["masses"][j] * (sum(arm["lengths"][k:j]) + arm["lengths"][j] / 2) ** 2
                          for j in range(k, n)) + arm["armature"][k]
            kp = inertia * arm["omega"][k] ** 2
            force = ' forcelimited="true" forcerange="%s %s"' % (fmt(-limit), fmt(limit)) \
                if arm["kind"] == "servo" else ""
            lines.append('    <position joint="joint%d" kp="%s" ctrllimited="true" ctrlrange="-3.14 3.14"%s/>' %
                         (k, fmt(kp), force))
    lines.append("  </actuator>")
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n"


CIRCLE_TOLERANCE = 5e-3  # [m] RMS over the last half of the run


def task_of(arm, name, kind):
    """The task file's content: reach the arm's qref, or its tip follows a circle from q0."""
    task = {"schema": "idmpc-task/1", "model": name + ".xml", "q0": arm["q0"]}
    if kind == "reach":
        task["qref"] = arm["qref"]
    else:
        task.update({"qref": "q0", "target": {"frame": "tip"},
                     "reference": {"shape": "circle", "radius": 0.05, "frequency": 0.5}})
    return task


def last_half_rms(log):
    """RMS of |x − x_ref| over the rows of the second half of a run's log [m]."""
    with open(log) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    col = {name: header.index(name) for name in ("t", "x", "y", "z", "x_ref", "y_ref", "z_ref")}
    t_end = float(rows[-1][col["t"]])
    sq = [sum((float(r[col[a]]) - float(r[col[a + "_ref"]])) ** 2 for a in "xyz")
          for r in rows if float(r[col["t"]]) >= t_end / 2]
    return math.sqrt(sum(sq) / len(sq)) if sq else float("nan")


def run_one(job):
    idmpc, workdir, name, formulation, solver, kind = job
    task = os.path.join(workdir, name + ".json")
    summary = os.path.join(workdir, "%s_%s.summary.json" % (name, formulation))
    log = os.path.join(workdir, "%s_%s.csv" % (name, formulation))
    args = [idmpc, "swingup", "--task", task, "--quiet", "--formulation", formulation, "--solver", solver,
            "--summary", summary] + (["--log", log] if kind == "circle" else [])
    proc = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if proc.returncode not in (0, 2, 3):
        return {"name": name, "formulation": formulation, "error": proc.stderr.strip().splitlines()[-1:]}
    with open(summary) as f:
        s = json.load(f)
    out = {"name": name, "formulation": formulation, "reached": s["reached"], "diverged": s["diverged"],
           "final": s["final_q_error"], "excess": s.get("max_constraint_violation", 0.0),
           "p50_ms": s["p50_update_ms"], "notices": s.get("notices", []),
           "lambda": s.get("open_loop_rate", float("nan")), "Tf": s["task"]["cgmres"]["Tf"],
           "solver": s.get("solver", solver)}
    if kind == "circle":
        # the last half's RMS: the circle settled after the start and the default 1 s ramp
        out["final"] = float("nan") if s["diverged"] else last_half_rms(log)
        out["reached"] = not s["diverged"] and out["final"] < CIRCLE_TOLERANCE
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--solver", choices=["auto", "cgmres", "riccati"], default="auto")
    ap.add_argument("--task", choices=["reach", "circle"], default="reach")
    ap.add_argument("--idmpc", default=os.path.join(ROOT, "build", "src", "idmpc"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "reference", "arm_population.md"))
    ap.add_argument("--keep", help="write the arms and their tasks here (else a temporary directory)")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    arms = [draw_arm(rng, i) for i in range(a.arms)]
    gravcomp_rng = random.Random(a.seed + 104729)
    for arm in arms:
        draw_gravcomp(gravcomp_rng, arm)
    with tempfile.TemporaryDirectory() as tmp:
        work = a.keep or tmp
        os.makedirs(work, exist_ok=True)
        jobs = []
        for i, arm in enumerate(arms):
            name = "arm%03d" % i
            with open(os.path.join(work, name + ".xml"), "w") as f:
                f.write(mjcf(arm, name))
            with open(os.path.join(work, name + ".json"), "w") as f:
                json.dump(task_of(arm, name, a.task), f)
            for formulation in ("fd", "id"):
                jobs.append((a.idmpc, work, name, formulation, a.solver, a.task))
        results = {}
        with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
            for r in pool.map(run_one, jobs):
                results[(r["name"], r["formulation"])] = r
                status = "error" if "error" in r else ("reached" if r["reached"] else
                                                       "DIVERGED" if r["diverged"] else "not reached")
                print("%s %s: %s%s" % (r["name"], r["formulation"], status,
                                       "" if "error" in r else " (%.2g)" % r["final"]), flush=True)
    write_report(a, arms, results)


def write_report(a, arms, results):
    def rate(keys):
        runs = [results[k] for k in keys]
        ok = sum(1 for r in runs if r.get("reached"))
        return "%d/%d" % (ok, len(runs))

    names = ["arm%03d" % i for i in range(len(arms))]
    circle = a.task == "circle"
    task_text = ("the tip follows a circle of 5 cm radius at 0.5 Hz from the start (the task: the model, the start, "
                 "the frame and the circle); reached: RMS position error below 5 mm over the last half of the 6 s run"
                 if circle else "each task only the model, the start and a joint target 0.3–1 rad away per joint; "
                 "reached: within 5e-3 rad at 6 s")
    lines = ["# Generated arms with the defaults" + (": circle tracking" if circle else ""), "",
             "Generated by `tools/arm_population.py --arms %d --seed %d --solver %s --task %s` on %s, %d cores. "
             "%d arms drawn at random (the script's docstring gives the distributions: 2–7 dof, masses from "
             "about 0.03 to 40 kg per link, armature, damping, torque motors or position servos with and without "
             "forcerange, a third with gravity compensation on all or some links, a third starting stretched at a "
             "singular configuration); %s."
             % (a.arms, a.seed, a.solver, a.task, cpu_model(), os.cpu_count(), len(arms), task_text), ""]
    lines += ["| | FD reached | ID reached |", "|---|---|---|"]
    lines.append("| all arms | %s | %s |" % (rate([(n, "fd") for n in names]), rate([(n, "id") for n in names])))

    def by(label, key):
        groups = {}
        for nm, arm in zip(names, arms):
            groups.setdefault(key(arm), []).append(nm)
        for g in sorted(groups):
            lines.append("| %s %s | %s | %s |" % (label, g, rate([(n, "fd") for n in groups[g]]),
                                                 rate([(n, "id") for n in groups[g]])))

    by("dof", lambda arm: arm["n"])
    by("actuators:", lambda arm: arm["kind"].replace("_", " "))
    by("start:", lambda arm: "stretched (singular)" if arm["stretched"] else "random")
    by("mass scale:", lambda arm: "< 2 kg" if arm["scale"] < 2 else ("2–8 kg" if arm["scale"] < 8 else "> 8 kg"))
    by("damping:", lambda arm: "yes" if arm["damping"][0] > 0 else "no")
    by("armature:", lambda arm: "yes" if arm["armature"][0] > 0 else "no")
    by("gravcomp:", gravcomp_kind)

    # the open loop's growth over the horizon, e^{λT_f}, from the runs' summaries (the same model for
    # both formulations): above e^4.5 FD's single-shooting rollout is ill-conditioned for C/GMRES
    # (said at start where FD runs under C/GMRES)
    def open_loop(nm):
        r = results[(nm, "fd")]
        if "lambda" not in r:
            return "unknown"
        return "λT_f > 4.5" if r["lambda"] * r["Tf"] > 4.5 else "λT_f ≤ 4.5"
    groups = {}
    for nm in names:
        groups.setdefault(open_loop(nm), []).append(nm)
    for g in sorted(groups):
        lines.append("| open loop: %s | %s | %s |" % (g, rate([(n, "fd") for n in groups[g]]),
                                                    rate([(n, "id") for n in groups[g]])))
    diverged = {f: sum(1 for n in names if results[(n, f)].get("diverged")) for f in ("fd", "id")}
    errors = {f: sum(1 for n in names if "error" in results[(n, f)]) for f in ("fd", "id")}
    excess = {f: sum(1 for n in names if results[(n, f)].get("excess", 0) > 1e-6) for f in ("fd", "id")}
    lines += ["", "Diverged: FD %d, ID %d. Refused (exit 1): FD %d, ID %d. Runs whose horizon torques left the "
              "actuator range at the start of some update (the plant's clamp held them): FD %d, ID %d." %
              (diverged["fd"], diverged["id"], errors["fd"], errors["id"], excess["fd"], excess["id"]), ""]
    if a.solver == "auto":
        chosen = {f: sorted(n for n in names if results[(n, f)].get("solver") == "riccati") for f in ("fd", "id")}
        lines += ["Solver \"auto\" ran the Riccati recursion on %d of the %d arms (C/GMRES on the rest), the same in "
                  "both formulations: %s." % (len(chosen["fd"]), len(names), "yes" if chosen["fd"] == chosen["id"] else "NO"), ""]
    lines += ["## Runs that did not reach", "",
              "| arm | dof | actuators | scale [kg] | start | gravcomp | λ [1/s] | solver | FD | ID |",
              "|---|---|---|---|---|---|---|---|---|---|"]

    def outcome(r):
        if "error" in r:
            return "refused: " + " ".join(r["error"])
        if r["reached"]:
            return "reached"
        if circle:
            return "diverged" if r["diverged"] else "not reached (%.2g mm)" % (1e3 * r["final"])
        return ("diverged" if r["diverged"] else "not reached") + " (%.2g rad)" % r["final"]

    for nm, arm in zip(names, arms):
        fd, idr = results[(nm, "fd")], results[(nm, "id")]
        if fd.get("reached") and idr.get("reached"):
            continue
        lines.append("| %s | %d | %s | %.3g | %s | %s | %.3g | %s | %s | %s |" %
                     (nm, arm["n"], arm["kind"].replace("_", " "), arm["scale"],
                      "stretched" if arm["stretched"] else "random", gravcomp_kind(arm),
                      fd.get("lambda", float("nan")), fd.get("solver", a.solver), outcome(fd), outcome(idr)))
    write_lines(a.out, lines)


if __name__ == "__main__":
    main()
