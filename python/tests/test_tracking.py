"""Frame targets and moving references: frames and their kinematics, the trajectories, the task
fields, the controller's frame target and a tracking task's closed loop."""

import json

import numpy as np
import pytest

import idmpc
from conftest import MJCF

CIRCLE_TASKS = sorted(p.name for p in MJCF.glob("*_circle.json"))
TRACKING_DURATION = 0.5  # s of mjcf/ur5e_circle.json: inside the circle's 1 s ramp, already moving


def rot_y(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def vee(W):
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


@pytest.fixture(scope="module")
def ur5e():
    return idmpc.load_model(str(MJCF / "ur5e.xml"))


def short_circle_task(duration=TRACKING_DURATION):
    task = idmpc.load_task(str(MJCF / "ur5e_circle.json"))
    task.duration = duration
    return task


@pytest.fixture(scope="module")
def circle_run():
    """The UR5e's circle task, 0.5 s of it: the run and its record."""
    run = idmpc.TaskRun(short_circle_task())
    return run, run.run()


# --- frames and their kinematics


def test_frame_kinematics_of_a_planar_arm():
    # arm4: four unit links about world y from (0, 0, 4.5); a frame at the end of the last one
    model = idmpc.load_model(str(MJCF / "arm4.xml"))
    frame = idmpc.Frame("hand", 3, position=[0, 0, 1], rotation=rot_y(0.3))
    assert frame.link == 3 and frame.name == "hand"
    np.testing.assert_array_equal(frame.position, [0, 0, 1])
    q = np.array([0.4, -0.7, 1.1, 0.2])
    p, R, J = idmpc.frame_kinematics(model, frame, q)
    s = np.cumsum(q)
    np.testing.assert_allclose(p, [np.sin(s).sum(), 0, 4.5 + np.cos(s).sum()], atol=1e-12)
    np.testing.assert_allclose(R, rot_y(s[-1] + 0.3), atol=1e-12)
    assert J.shape == (6, 4)
    # every joint turns the frame about world y
    np.testing.assert_allclose(J[3:], np.tile([[0], [1], [0]], 4), atol=1e-12)


@pytest.mark.parametrize("file,name", [("ur5e.xml", "tip"), ("panda.xml", "tip"), ("panda.xml", "link5")])
def test_jacobian_is_the_derivative_of_the_pose(file, name):
    model = idmpc.load_model(str(MJCF / file))
    frame = idmpc.load_frame(str(MJCF / file), name)
    q = np.random.default_rng(3).uniform(-1, 1, model.n)
    _, R, J = idmpc.frame_kinematics(model, frame, q)
    h = 1e-6
    for j in range(model.n):
        dq = np.zeros(model.n)
        dq[j] = h
        p_plus, R_plus, _ = idmpc.frame_kinematics(model, frame, q + dq)
        p_minus, R_minus, _ = idmpc.frame_kinematics(model, frame, q - dq)
        np.testing.assert_allclose(J[:3, j], (p_plus - p_minus) / (2 * h), atol=1e-8, err_msg=f"jacp column {j}")
        # dR/dq_j = [w_j]x R
        np.testing.assert_allclose(J[3:, j], vee((R_plus - R_minus) / (2 * h) @ R.T), atol=1e-8,
                                   err_msg=f"jacr column {j}")


def test_load_frame_is_the_task_runs_frame(circle_run):
    run, _ = circle_run
    frame = idmpc.load_frame(str(MJCF / "ur5e.xml"), "tip")
    again = run.frame("tip")
    assert frame.name == again.name == "site 'tip'"
    assert frame.link == again.link == run.n - 1
    np.testing.assert_array_equal(frame.position, again.position)
    np.testing.assert_array_equal(frame.rotation, again.rotation)
    assert idmpc.load_frame(str(MJCF / "ur5e.xml"), "world").link == -1


def test_tip_at_q0_is_the_targets_start(circle_run):
    run, _ = circle_run
    target = run.frame_target
    assert isinstance(target, idmpc.FrameTarget) and target.frame.name == "site 'tip'"
    np.testing.assert_array_equal(target.position_weight, [1e4] * 3)
    assert target.orientation_weight == 100
    p, R, _ = idmpc.frame_kinematics(run.model, run.frame("tip"), run.q0)
    np.testing.assert_allclose(target.position, p, rtol=0, atol=1e-12)
    np.testing.assert_allclose(target.rotation, R, rtol=0, atol=1e-12)
    # the circle passes through the start, at rest
    assert isinstance(run.reference, idmpc.CircleTrajectory)
    value, rate = run.reference.sample(0.0)
    np.testing.assert_allclose(value, p, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rate, np.zeros(3))


def test_unknown_frame_is_a_value_error_with_the_cpp_message(ur5e):
    path = str(MJCF / "ur5e.xml")
    message = f"model '{path}' has no site or body 'nose' (sites: tip)"
    with pytest.raises(ValueError) as e:
        idmpc.load_frame(path, "nose")
    assert str(e.value) == message
    task = short_circle_task()
    target = task.target
    target.frame = "nose"
    task.target = target
    with pytest.raises(ValueError) as e:
        idmpc.TaskRun(task)
    assert str(e.value) == message


def test_frame_that_does_not_fit_the_model_is_a_value_error(ur5e):
    with pytest.raises(ValueError) as e:
        idmpc.frame_kinematics(ur5e, idmpc.Frame("far", 6), np.zeros(6))
    assert str(e.value) == f"far of model '{ur5e.name}': link 6 is not a link of the model: expected -1 (the base) to 5"
    with pytest.raises(ValueError, match="placement rotation must be orthonormal"):
        idmpc.frame_kinematics(ur5e, idmpc.Frame("squashed", 5, rotation=np.diag([1.0, 1.0, 2.0])), np.zeros(6))
    with pytest.raises(ValueError, match="frame_kinematics: q has 5 entries, expected n = 6"):
        idmpc.frame_kinematics(ur5e, idmpc.Frame("tip", 5), np.zeros(5))


def test_rotation_angle():
    assert idmpc.rotation_angle(rot_y(0.7), np.eye(3)) == pytest.approx(0.7, abs=1e-12)
    assert idmpc.rotation_angle(rot_y(0.2), rot_y(-0.3)) == pytest.approx(0.5, abs=1e-12)
    assert idmpc.rotation_angle(np.eye(3), np.eye(3)) == 0


# --- trajectories


def central_rate(trajectory, t, h=1e-6):
    return (trajectory.sample(t + h)[0] - trajectory.sample(t - h)[0]) / (2 * h)


def test_circle_trajectory():
    c, normal, e1 = np.array([0.4, 0.1, 0.6]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    circle = idmpc.CircleTrajectory(c, normal, radius=0.05, frequency=0.5, e1=e1, ramp=1.0)
    assert circle.dim == 3 and circle.radius == 0.05 and circle.ramp == 1.0
    np.testing.assert_allclose(circle.e2, np.cross(normal, e1))
    value, rate = circle.sample(0.0)
    np.testing.assert_allclose(value, c + 0.05 * e1, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(rate, np.zeros(3))
    times = np.linspace(-0.5, 4.0, 46)
    values, rates = circle.sample(times)
    assert values.shape == rates.shape == (46, 3)
    np.testing.assert_allclose(np.linalg.norm(values - c, axis=1), 0.05, rtol=1e-12)
    np.testing.assert_allclose((values - c) @ normal, 0, atol=1e-15)
    for t, rate in zip(times, rates):
        if abs(t) > 1e-3:  # the rate is continuous but the start is a kink of the phase's 3rd derivative
            np.testing.assert_allclose(rate, central_rate(circle, t), atol=1e-8, err_msg=f"t = {t}")
    # after the ramp: full speed 2 pi f r
    np.testing.assert_allclose(np.linalg.norm(rates[times > 1.0], axis=1), 2 * np.pi * 0.5 * 0.05, rtol=1e-12)
    assert circle.phase(2.0)[1] == pytest.approx(np.pi)
    assert "circle" in circle.describe() and repr(circle).startswith("<idmpc.CircleTrajectory circle")


def test_waypoint_trajectory():
    times = [0.0, 1.0, 3.0]
    points = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, -1.0]])
    w = idmpc.WaypointTrajectory(times, points)
    assert w.dim == 2 and w.times == times
    np.testing.assert_array_equal(w.values, points)
    values, rates = w.sample(np.array(times))
    np.testing.assert_allclose(values, points, atol=1e-15)
    np.testing.assert_allclose(rates, 0, atol=1e-15)  # at rest at every waypoint
    for t in [0.3, 0.5, 1.7, 2.9]:
        np.testing.assert_allclose(w.sample(t)[1], central_rate(w, t), atol=1e-8)
    # minimum jerk: halfway in time is halfway in value, at 15/8 of the mean speed
    value, rate = w.sample(2.0)
    np.testing.assert_allclose(value, [1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(rate, [0.0, -1.875], atol=1e-12)
    # held before the first and after the last
    np.testing.assert_array_equal(w.sample(-1.0)[0], points[0])
    np.testing.assert_array_equal(w.sample(9.0)[0], points[-1])


def test_sampled_trajectory_and_csv(tmp_path):
    times = np.array([0.0, 0.1, 0.25, 0.4])
    values = np.column_stack([2 * times + 1, times**2])
    s = idmpc.SampledTrajectory(times, values)
    np.testing.assert_allclose(s.sample(times)[0], values, atol=1e-15)
    for t in [0.05, 0.2, 0.3]:
        value, rate = s.sample(t)
        assert value[0] == pytest.approx(2 * t + 1, abs=1e-14)  # a uniform motion exactly
        assert rate[0] == pytest.approx(2.0, abs=1e-12)
        np.testing.assert_allclose(rate, central_rate(s, t), atol=1e-7)
    assert s.tangents.shape == (4, 2)
    path = tmp_path / "plan.csv"
    path.write_text("t,x,y\n# a planner's output\n" + "\n".join(
        f"{t!r},{x!r},{y!r}" for t, (x, y) in zip(times, values)) + "\n")
    read = idmpc.read_trajectory_csv(str(path), 2)
    assert isinstance(read, idmpc.SampledTrajectory) and read.times == times.tolist()
    np.testing.assert_array_equal(read.values, values)
    path.write_text("0,1,2\n0.1,1,zwei\n")
    with pytest.raises(ValueError, match=r"plan\.csv.*line 2.*zwei"):
        idmpc.read_trajectory_csv(str(path), 2)


def test_constant_trajectory():
    c = idmpc.ConstantTrajectory([1.0, 2.0])
    value, rate = c.sample(5)
    np.testing.assert_array_equal(value, [1.0, 2.0])
    np.testing.assert_array_equal(rate, [0.0, 0.0])


def test_trajectory_from_dict(tmp_path):
    start = np.array([0.3, 0.0, 0.5])
    circle = idmpc.trajectory_from_dict({"shape": "circle", "radius": 0.05, "frequency": 0.5}, start)
    assert isinstance(circle, idmpc.CircleTrajectory) and circle.radius == 0.05
    np.testing.assert_allclose(circle.sample(0.0)[0], start, atol=1e-15)
    line = idmpc.trajectory_from_dict({"shape": "line", "to": [0.3, 0.1, 0.5], "duration": 2.0}, start)
    np.testing.assert_allclose(line.sample(2.0)[0], [0.3, 0.1, 0.5])
    (tmp_path / "plan.csv").write_text("0,0.3,0,0.5\n1,0.3,0.2,0.5\n")
    csv = idmpc.trajectory_from_dict({"shape": "csv", "file": "plan.csv"}, start, base_dir=str(tmp_path))
    np.testing.assert_allclose(csv.sample(1.0)[0], [0.3, 0.2, 0.5])
    with pytest.raises(ValueError, match="my reference.*radius"):
        idmpc.trajectory_from_dict({"shape": "circle", "radius": -1, "frequency": 0.5}, start, where="my reference")


@pytest.mark.parametrize("make,message", [
    (lambda: idmpc.CircleTrajectory([0, 0, 0], [1, 0, 0], -0.1, 0.5, [0, 0, 1]), "radius"),
    (lambda: idmpc.CircleTrajectory([0, 0, 0], [1, 0, 0], 0.1, 0.5, [1, 0, 0]), "e1"),
    (lambda: idmpc.WaypointTrajectory([0.0, 1.0], np.zeros((3, 2))), "values has 3 rows, expected one per time"),
    (lambda: idmpc.SampledTrajectory([0.0, 0.0], np.zeros((2, 1))), "increasing"),
    (lambda: idmpc.ConstantTrajectory([np.nan]), "finite"),
])
def test_bad_trajectories_are_value_errors(make, message):
    with pytest.raises(ValueError, match=message):
        make()


# --- tasks


def test_circle_task_fields():
    task = idmpc.load_task(str(MJCF / "ur5e_circle.json"))
    with open(MJCF / "ur5e_circle.json") as f:
        file = json.load(f)
    assert task.qref_start and task.qref == []
    target = task.target
    assert isinstance(target, idmpc.FrameTask)
    assert (target.frame, target.position, target.orientation) == ("tip", [], [])
    assert target.position_weight == [1e4] and target.orientation_weight == 100
    assert idmpc.FrameTask("tip").orientation_weight is None  # not given: "auto"
    assert task.reference == file["reference"]
    assert task.tracking_tolerance == 5e-3
    # fields are copies: assign a whole value
    task.target.frame = "elsewhere"
    task.reference["radius"] = 1.0
    assert task.target.frame == "tip" and task.reference["radius"] == 0.05
    task.target = idmpc.FrameTask("tip", position=[0.3, 0.1, 0.4], position_weight=[1, 2, 3])
    task.reference = None
    d = task.to_dict()
    assert d["target"]["position"] == [0.3, 0.1, 0.4] and d["target"]["weights"]["position"] == [1, 2, 3]
    assert "reference" not in d or d["reference"] is None
    task.target = None
    assert task.target is None and "target" not in task.to_dict()


@pytest.mark.parametrize("name", CIRCLE_TASKS)
def test_circle_task_dict_round_trip(name):
    d = idmpc.load_task(str(MJCF / name)).to_dict()
    assert idmpc.task_from_dict(d).to_dict() == d
    assert d["qref"] == "q0" and d["target"]["frame"] and d["reference"]["shape"] == "circle"


def test_qref_q0_from_a_dict():
    task = idmpc.task_from_dict({"model": str(MJCF / "ur5e.xml"), "q0": "home", "qref": "q0", "duration": 0.01})
    assert task.qref_start
    run = idmpc.TaskRun(task)
    np.testing.assert_array_equal(run.controller.q_ref, run.q0)
    assert run.frame_target is None and run.reference is None


# --- the closed loop


def test_tracking_run_record(circle_run):
    run, r = circle_run
    steps = len(r["t"])
    assert r["frame_position"].shape == r["frame_target"].shape == (steps, 3)
    tracking = r["summary"]["tracking"]
    assert r["summary"]["diverged"] is False and r["updates"] == steps
    # 0.2 mm, within the task's tolerance by far (a target held at the start instead: 5.8 mm)
    assert tracking["position_rms"] < min(1e-3, run.task.tracking_tolerance)
    # each row's target is the reference at its time; the frame is measured on the plant
    np.testing.assert_allclose(r["frame_target"], run.reference.sample(r["t"])[0], rtol=0, atol=1e-15)
    for k in [0, steps // 2, steps - 1]:
        p, _, _ = idmpc.frame_kinematics(run.model, run.frame("tip"), r["q"][k])
        np.testing.assert_allclose(r["frame_position"][k], p, rtol=0, atol=1e-9)
    # the summary's errors are the rows' and the final state's
    e = np.linalg.norm(r["frame_position"] - r["frame_target"], axis=1)
    assert tracking["samples"] == steps + 1
    assert tracking["position_rms"] ** 2 * (steps + 1) == pytest.approx(
        (e**2).sum() + tracking["final_position_error"] ** 2, rel=1e-9)
    assert tracking["position_max"] >= e.max()
    # the circle has started: the target moved by more than the error
    assert np.linalg.norm(r["frame_target"][-1] - r["frame_target"][0]) > 5 * tracking["position_rms"]


def test_joint_task_has_no_tracking():
    task = idmpc.paper_task()
    task.duration = 0.01
    r = idmpc.run_task(task)
    assert "frame_position" not in r and "frame_target" not in r and "tracking" not in r["summary"]


def test_controller_settings_frame_target_drives_a_python_loop(circle_run):
    """A controller of our own with the task run's frame target and reference: a loop in Python on
    the run's plant tracks the circle as the task's own controller does."""
    run, _ = circle_run
    settings = idmpc.ControllerSettings()
    assert settings.frame_target is None and settings.frame_reference is None and settings.joint_reference is None
    n = run.n
    settings.weights.Qq, settings.weights.Qv = np.ones(n), np.ones(n)
    settings.weights.R = 1e-3 * np.ones(n)
    settings.q_ref = run.q0
    settings.torque_lower, settings.torque_upper = run.torque_lower, run.torque_upper
    settings.cgmres.alpha = 0.0
    settings.cgmres.init_full_horizon = True
    settings.frame_target = run.frame_target
    settings.frame_reference = run.reference
    assert settings.frame_reference is run.reference
    np.testing.assert_array_equal(settings.frame_target.position, run.frame_target.position)
    controller = idmpc.Controller(run.model, settings)
    plant, frame, reference = run.plant, run.frame("tip"), run.reference
    dt = controller.dt
    plant.reset(run.q0, np.zeros(n))
    tau = controller.initialize(plant.q, plant.v)
    errors = []
    for k in range(int(round(TRACKING_DURATION / dt))):
        t = k * dt
        assert controller.update(t, plant.q, plant.v), controller.failure
        errors.append(np.linalg.norm(idmpc.frame_kinematics(run.model, frame, plant.q)[0] - reference.sample(t)[0]))
        ok, reason = plant.step(tau)
        assert ok, reason
        tau = controller.torque
    # 0.2 mm as the task's own run; without the frame reference (the target held at the start): 5.8 mm
    assert np.sqrt(np.mean(np.square(errors))) < 1e-3


def test_controller_set_frame_target():
    run = idmpc.TaskRun(short_circle_task())
    controller = run.controller
    target = controller.frame_target
    np.testing.assert_array_equal(target.position, run.frame_target.position)
    p = target.position + [0.0, 0.0, 0.01]
    R = run.frame_target.rotation @ rot_y(0.1)
    controller.set_frame_target(p, R)
    np.testing.assert_array_equal(controller.frame_target.position, p)
    np.testing.assert_allclose(controller.frame_target.rotation, R, atol=0)
    with pytest.raises(ValueError, match="rotation is not a rotation matrix"):
        controller.set_frame_target(p, 2 * R)
    joint_only = idmpc.TaskRun(idmpc.paper_task()).controller
    assert joint_only.frame_target is None
    with pytest.raises(ValueError, match="no frame target"):
        joint_only.set_frame_target(p, R)


def test_frame_reference_without_a_frame_target_is_a_value_error(arm4):
    settings = idmpc.ControllerSettings()
    settings.weights.Qq, settings.weights.Qv, settings.weights.R = np.ones(4), np.ones(4), np.ones(4)
    settings.q_ref = np.zeros(4)
    settings.frame_reference = idmpc.ConstantTrajectory([0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="the problem has no frame target"):
        idmpc.Controller(arm4, settings)
    settings.frame_reference = None
    settings.joint_reference = idmpc.ConstantTrajectory(np.zeros(4))
    assert idmpc.Controller(arm4, settings).n == 4
