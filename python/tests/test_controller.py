"""The controller and the closed loop: a task's run and its record, a loop written in Python
with the plant and the controller that gives the same run, and the errors of bad tasks."""

import gc
import threading

import numpy as np
import pytest

import idmpc
from conftest import MJCF

DURATION = 0.3  # s: 300 control steps of the paper's swing-up, enough to move and to compare
MAX_SPEED = 1e4  # rad/s: the closed loop's divergence threshold (closed_loop.cpp)


def short_paper_task(formulation="id"):
    task = idmpc.paper_task()
    task.duration = DURATION
    task.formulation = formulation
    return task


@pytest.fixture(scope="module", params=["id", "fd"])
def record(request):
    task = short_paper_task(request.param)
    return task, idmpc.run_task(task)


def test_record_shapes(record):
    task, r = record
    steps = int(np.floor(DURATION / task.dt + 0.5))
    assert r["t"].shape == r["residual"].shape == r["update_ms"].shape == (steps,)
    for key in ["q", "v", "u", "u_commanded"]:
        assert r[key].shape == (steps, 4), key
        assert r[key].dtype == np.float64 and r[key].flags["C_CONTIGUOUS"], key
    np.testing.assert_allclose(r["t"], np.arange(steps) * task.dt, rtol=0, atol=1e-12)
    # the first row is the measured initial state: the swing-up's (-pi, 0, 0, 0) at rest
    np.testing.assert_array_equal(r["q"][0], [-np.pi, 0, 0, 0])
    np.testing.assert_array_equal(r["v"][0], np.zeros(4))
    assert np.all(np.isfinite(r["residual"])) and np.all(r["update_ms"] > 0)


def test_summary_matches_the_record(record):
    task, r = record
    s = r["summary"]
    assert s["n"] == 4 and s["steps"] == len(r["t"])
    assert s["diverged"] is False
    assert s["task"]["duration"] == DURATION and s["task"]["formulation"] == task.formulation
    assert s["mean_residual"] == pytest.approx(r["residual"].mean(), rel=1e-12)
    assert s["mean_update_ms"] == pytest.approx(r["update_ms"].mean(), rel=1e-9)
    assert s["max_update_ms"] == r["update_ms"].max()
    assert r["updates"] == s["steps"]
    clamped = r["u"] != r["u_commanded"]
    assert s["saturated_any"] == int(clamped.any(axis=1).sum())
    assert s["saturated_steps"] == clamped.sum(axis=0).tolist()
    # the applied torques lie within the limits the summary reports (JSON null: unbounded)
    lower = np.array([-np.inf if x is None else x for x in s["torque_lower"]])
    upper = np.array([np.inf if x is None else x for x in s["torque_upper"]])
    assert np.all(r["u"] >= lower) and np.all(r["u"] <= upper)


def test_task_run_accessors():
    run = idmpc.TaskRun(short_paper_task())
    assert run.n == 4 and run.model.n == 4 and run.model.joint_names == ["joint0", "joint1", "joint2", "joint3"]
    np.testing.assert_array_equal(run.q0, [-np.pi, 0, 0, 0])
    assert run.controller.n == 4 and run.controller.dt == 1e-3
    assert run.plant.nv == 4
    assert run.torque_lower.shape == run.torque_upper.shape == (4,)
    assert isinstance(run.notices, list) and isinstance(run.warnings, list)
    assert run.task.duration == DURATION
    run.task.duration = 5.0  # a copy: the run keeps its task
    assert run.task.duration == DURATION


def python_loop(run, controller=None):
    """run_closed_loop (closed_loop.cpp) step by step: initialize at the measured x(0), then per
    step update at t from the measured state, apply the torque of the previous update for one
    period and take the new one. controller: the run's own unless given."""
    plant, controller = run.plant, controller or run.controller
    dt = controller.dt
    steps = int(np.floor(run.task.duration / dt + 0.5))
    plant.reset(run.q0, np.zeros(run.n))
    tau = controller.initialize(plant.q, plant.v)
    assert controller.failure == ""
    updates = 0
    for k in range(steps):
        if not controller.update(k * dt, plant.q, plant.v):
            break
        updates += 1
        ok, reason = plant.step(tau)
        assert ok, reason
        if np.abs(plant.v).max() > MAX_SPEED:
            break
        tau = controller.torque
    return updates, np.abs(plant.q - controller.q_ref).max()


def short_reach_task(formulation):
    """The Panda's reach (offset-free tracking, full-horizon start, torque limits), 0.1 s of it."""
    task = idmpc.load_task(str(MJCF / "panda_reach.json"))
    task.duration = 0.1
    task.formulation = formulation
    return task


# the Panda's full-horizon start takes seconds in FD (50 Newton steps with dense derivatives)
@pytest.mark.parametrize("make,formulation", [(short_paper_task, "id"), (short_paper_task, "fd"),
                                              (short_reach_task, "id")], ids=["arm4-id", "arm4-fd", "panda-id"])
def test_python_loop_is_the_cpp_loop(make, formulation):
    task = make(formulation)
    r = idmpc.TaskRun(task).run()
    updates, error = python_loop(idmpc.TaskRun(task))
    assert updates == r["updates"] == r["summary"]["steps"]
    assert error == r["summary"]["final_q_error"]
    assert error > 0.1  # 0.3 s into the motion: far from the target, a meaningful comparison


def test_torque_limit_clamps_the_applied_torque():
    task = short_paper_task()
    task.torque_limit = [5.0]
    r = idmpc.run_task(task)
    s = r["summary"]
    assert s["torque_lower"] == [-5.0] * 4 and s["torque_upper"] == [5.0] * 4
    assert np.abs(r["u"]).max() <= 5.0
    clamped = r["u"] != r["u_commanded"]
    # where clamped, the command was beyond the limit and the applied torque is the limit
    assert clamped.sum() > 100
    assert np.all(np.abs(r["u_commanded"][clamped]) > 5.0)
    np.testing.assert_array_equal(np.abs(r["u"][clamped]), 5.0)
    # the summary counts the steps of successful updates (a failed last update's row is logged)
    assert s["saturated_any"] == int(clamped[: r["updates"]].any(axis=1).sum())
    assert s["saturated_steps"] == clamped[: r["updates"]].sum(axis=0).tolist()
    if s["diverged"]:
        assert s["diverged_at"] == r["t"][-1] and s["divergence_reason"]
        assert s["divergence_hint"].startswith("try ")


def test_run_after_a_python_loop_starts_afresh():
    task = short_paper_task()
    expected = idmpc.run_task(task)
    run = idmpc.TaskRun(task)
    python_loop(run)
    again = run.run()
    np.testing.assert_array_equal(again["q"], expected["q"])
    assert again["summary"]["final_q_error"] == expected["summary"]["final_q_error"]


def test_controller_and_plant_keep_their_run_alive():
    controller = idmpc.TaskRun(short_paper_task()).controller
    plant = idmpc.TaskRun(short_paper_task()).plant
    gc.collect()
    plant.reset([-np.pi, 0, 0, 0], np.zeros(4))
    tau = controller.initialize(plant.q, plant.v)
    assert plant.step(tau) == (True, "")
    assert plant.time == pytest.approx(controller.dt)


def test_runs_in_threads_equal_the_serial_run():
    task = short_paper_task()
    expected = idmpc.run_task(task)
    records = [None, None]

    def run(i):
        records[i] = idmpc.run_task(task)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in records:
        np.testing.assert_array_equal(r["q"], expected["q"])
        np.testing.assert_array_equal(r["u"], expected["u"])


def test_controller_settings_defaults_are_the_cpp_defaults():
    s = idmpc.ControllerSettings()
    assert (s.formulation, s.derivatives, s.N) == ("id", "adjoint", 25)
    assert (s.cgmres.kmax, s.cgmres.Tf, s.cgmres.dt, s.cgmres.shooting) == (10, 0.5, 1e-3, "single")
    assert s.cgmres.products == "difference"
    assert s.q_ref.shape == (0,) and s.limits_in_horizon
    assert s.friction_loss.shape == s.friction_velocity.shape == s.q_start.shape == (0,)
    assert (s.implicit_damping, s.plant_step) == ("off", 0.0)


def test_a_controller_from_the_runs_settings_is_the_runs():
    # the xArm7 has friction loss (smoothed in the horizon) and damping (implicit over the plant
    # step in the torque rule): the settings carry them, and the controller chooses the same
    task = idmpc.load_task(str(MJCF / "xarm7_reach.json"))
    task.duration = 0.05
    run = idmpc.TaskRun(task)
    settings = run.settings
    assert settings.friction_loss.max() > 0 and settings.plant_step > 0
    by_run = python_loop(run)
    mine = idmpc.Controller(run.model, settings)
    assert python_loop(idmpc.TaskRun(task), mine) == by_run
    with pytest.raises(ValueError, match="implicit damping: expected"):
        settings.implicit_damping = "sometimes"


def test_controller_from_settings():
    model = idmpc.load_model(str(MJCF / "arm4.xml"))
    settings = idmpc.ControllerSettings()
    settings.formulation = "fd"
    settings.derivatives = "matrix"
    settings.N = 10
    settings.cgmres.Tf = 0.2
    settings.weights.Qq = np.ones(4)
    settings.weights.Qv = 0.1 * np.ones(4)
    settings.weights.R = 1e-4 * np.ones(4)
    settings.q_ref = np.zeros(4)
    assert settings.cgmres.Tf == 0.2 and settings.formulation == "fd"
    controller = idmpc.Controller(model, settings)
    del model  # the controller keeps its model
    q, v = np.array([-0.5, 0, 0, 0]), np.zeros(4)
    tau = controller.initialize(q, v)
    assert tau.shape == (4,) and np.all(np.isfinite(tau))
    assert controller.update(0.0, q, v) and controller.failure == ""
    # the same controller with exact products takes the same step to rounding
    settings.cgmres.products = "exact"
    exact = idmpc.Controller(idmpc.load_model(str(MJCF / "arm4.xml")), settings)
    np.testing.assert_allclose(exact.initialize(q, v), tau, rtol=1e-9, atol=1e-9)
    assert exact.update(0.0, q, v)
    np.testing.assert_allclose(exact.torque, controller.torque, rtol=1e-5, atol=1e-6)
    controller.set_target(np.full(4, 0.1))
    np.testing.assert_array_equal(controller.q_ref, np.full(4, 0.1))
    with pytest.raises(ValueError, match="update: q has 3 entries, expected n = 4"):
        controller.update(0.0, q[:3], v)


def test_bad_settings_are_value_errors():
    settings = idmpc.ControllerSettings()
    with pytest.raises(ValueError, match="fdd"):
        settings.formulation = "fdd"
    with pytest.raises(ValueError, match="tangential"):
        settings.cgmres.shooting = "tangential"
    with pytest.raises(ValueError, match="products must be 'difference' or 'exact', got 'finite'"):
        settings.cgmres.products = "finite"


@pytest.mark.parametrize("field,value,message", [
    ("qref", [0.0, 0.0, 0.0], "--qref (qref) has 3 values, expected 1 or 4 (one per joint)"),
    ("Qq", [-1.0], "--Qq (weights.Qq) must be finite and non-negative, got -1.000000"),
    ("duration", -1.0, "duration must be positive, got -1.000000"),
    ("formulation", "pd", "unknown formulation 'pd': expected 'fd' or 'id'"),
    ("N", 0, "--N (cgmres.N) must be from 1 to 10000 horizon steps, got 0"),
    ("dt", 0.0, "sampling period dt must be positive, got 0"),
])
def test_bad_task_values_are_value_errors_with_the_cpp_message(field, value, message):
    task = short_paper_task()
    setattr(task, field, value)
    with pytest.raises(ValueError) as e:
        idmpc.run_task(task)
    assert str(e.value) == message


def test_missing_model_is_a_runtime_error(tmp_path):
    task = short_paper_task()
    task.model = str(tmp_path / "none.xml")
    with pytest.raises(RuntimeError, match="none.xml"):
        idmpc.TaskRun(task)


# the command line and the Python loop run the same task to the same result; the binary comes
# from ctest's environment (IDMPC_BINARY), or is skipped when pytest runs on its own
@pytest.mark.parametrize("formulation", ["id", "fd"])
def test_python_loop_is_the_command_line(formulation, tmp_path):
    import json
    import os
    import subprocess

    binary = os.environ.get("IDMPC_BINARY")
    if not binary:
        pytest.skip("IDMPC_BINARY is not set (ctest sets it)")
    summary = tmp_path / "summary.json"
    done = subprocess.run([binary, "swingup", "--formulation", formulation, "--duration", str(DURATION),
                           "--summary", str(summary)], capture_output=True, text=True)
    assert done.returncode in (0, 2), done.stderr  # reached or not: a completed run
    cli = json.loads(summary.read_text())
    updates, error = python_loop(idmpc.TaskRun(short_paper_task(formulation)))
    assert updates == cli["steps"]
    assert error == cli["final_q_error"]


def test_the_riccati_solver_from_a_task_and_from_settings():
    # the same task under the Riccati solver: its record names it, and the loop does not diverge
    task = short_paper_task("fd")
    task.solver = "riccati"
    task.riccati.iterations = 2
    s = idmpc.run_task(task)["summary"]
    assert s["diverged"] is False
    assert s["task"]["solver"] == "riccati" and s["task"]["riccati"]["iterations"] == 2
    # a controller built by hand with the settings type
    settings = idmpc.ControllerSettings()
    settings.solver = "riccati"
    assert settings.solver == "riccati"
    settings.riccati.barrier = 1e-2
    assert settings.riccati.barrier == 1e-2
    with pytest.raises(ValueError, match="newton"):
        settings.solver = "newton"
    bad = idmpc.RiccatiSettings()
    bad.iterations = 0
    with pytest.raises(ValueError, match="iterations"):
        bad.validate()


def test_auto_solver_is_resolved_on_the_model_and_recorded():
    # a task defaults to "auto": the Riccati recursion on a real arm (whatever its horizon), C/GMRES
    # on the cart-pole (under-actuated), the same in both formulations; the run's task, controller
    # and summary all name the one chosen
    for name, expected in (("ur5e_reach.json", "riccati"), ("cartpole_swingup.json", "cgmres")):
        task = idmpc.load_task(str(MJCF / name))
        assert task.solver == "auto"
        task.duration = 0.01
        for tf in (0.1, 2.0):
            for formulation in ("fd", "id"):
                task.Tf = tf
                task.formulation = formulation
                run = idmpc.TaskRun(task)
                assert run.controller.solver == expected
                assert run.task.solver == expected
                assert run.settings.solver == expected
                assert run.run()["summary"]["task"]["solver"] == expected
        # a controller built by hand from settings with "auto" says which it runs
        run = idmpc.TaskRun(task)
        settings = run.settings
        settings.solver = "auto"
        assert idmpc.Controller(run.model, settings).solver == expected


@pytest.mark.parametrize("solver", ["cgmres", "riccati"])
@pytest.mark.parametrize("formulation", ["fd", "id"])
def test_under_actuated_task_runs_from_python_and_leaves_the_passive_joint_alone(formulation, solver):
    # the shipped cart-pole swing-up, its first 0.3 s, under either solver: the hinge has no actuator
    task = idmpc.load_task(str(MJCF / "cartpole_swingup.json"))
    task.formulation = formulation
    task.solver = solver
    task.duration = 0.3
    run = idmpc.TaskRun(task)
    assert run.model.unactuated_joints == [1] and run.model.actuated_joints == [0]
    assert np.isinf(run.torque_lower[1]) and np.isinf(run.torque_upper[1])
    r = run.run()
    assert r["summary"]["diverged"] is False and r["summary"]["task"].get("solver", "cgmres") == solver
    assert np.all(r["u"][:, 1] == 0) and np.all(r["u_commanded"][:, 1] == 0)
    assert np.all(np.abs(r["u"][:, 0]) <= 10) and np.abs(r["u"][:, 0]).max() > 5


@pytest.mark.parametrize("formulation", ["fd", "id"])
def test_the_acrobot_swing_up_runs_from_python(formulation):
    # the shipped Riccati task, its first 0.5 s: the elbow pumps within its 10 N m, the shoulder gets nothing
    task = idmpc.load_task(str(MJCF / "acrobot_swingup.json"))
    task.formulation = formulation
    task.duration = 0.5
    r = idmpc.TaskRun(task).run()
    assert r["summary"]["diverged"] is False and r["summary"]["task"]["solver"] == "riccati"
    assert np.all(r["u"][:, 0] == 0) and np.all(r["u_commanded"][:, 0] == 0)
    assert np.all(np.abs(r["u"][:, 1]) <= 10) and np.abs(r["u"][:, 1]).max() > 5
