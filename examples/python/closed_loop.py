#!/usr/bin/env python3
"""A closed loop written in Python with idmpc's plant and controller, then the same task run by
the library's loop (TaskRun.run). Build tree:

    PYTHONPATH=build/python /usr/bin/python3 examples/python/closed_loop.py [TASK.json]

Without an argument: the paper's swing-up on arm4, shortened to 0.3 s. A shipped reach task,
e.g. mjcf/panda_reach.json, runs as its file says.
"""

import sys

import numpy as np

import idmpc

if len(sys.argv) > 1:
    task = idmpc.load_task(sys.argv[1])
else:
    task = idmpc.paper_task()
    task.duration = 0.3

run = idmpc.TaskRun(task)
for line in run.notices:
    print("notice:", line)
for line in run.warnings:
    print("warning:", line)
plant, controller = run.plant, run.controller

# the library's sequence: initialize at x(0); per step, update at t from the measured state,
# apply the previous update's torque for one period, then take the new one
dt = controller.dt
plant.reset(run.q0, np.zeros(run.n))
tau = controller.initialize(plant.q, plant.v)
updates = 0
for k in range(int(np.floor(task.duration / dt + 0.5))):
    if not controller.update(k * dt, plant.q, plant.v):
        print("diverged at t =", k * dt, ":", controller.failure)
        break
    updates += 1
    ok, reason = plant.step(tau)
    if not ok:
        print("the simulation failed:", reason)
        break
    tau = controller.torque
error = np.abs(plant.q - controller.q_ref).max()
print(f"Python loop:   {updates} updates, final max|q - q_ref| = {error:.6g}")

record = idmpc.TaskRun(task).run()
library_error = record["summary"]["final_q_error"]
print(f"TaskRun.run(): {record['updates']} updates, final max|q - q_ref| = {library_error:.6g}")
if (updates, error) != (record["updates"], library_error):
    sys.exit("the Python loop and the library's loop differ")
