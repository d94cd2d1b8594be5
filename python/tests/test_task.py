"""Tasks: the shipped files through load_task and paper_task, the fields as attributes, the dict
form (to_dict / task_from_dict) and the errors, with the C++ messages."""

import copy
import json

import numpy as np
import pytest

import idmpc
from conftest import MJCF

REACH_TASKS = sorted(p.name for p in MJCF.glob("*_reach.json"))


def test_paper_task_is_the_shipped_file():
    task = idmpc.paper_task()
    with open(MJCF / "paper_swingup.json") as f:
        file = json.load(f)
    assert idmpc.paper_task_path().endswith("paper_swingup.json")
    assert task.q0_rule == file["q0"] == "swingup" and task.q0 == []
    assert task.duration == file["duration"]
    assert task.formulation == file["formulation"] and task.derivatives == file["derivatives"]
    assert (task.N, task.kmax, task.Tf, task.alpha, task.dt) == tuple(
        file["cgmres"][k] for k in ["N", "kmax", "Tf", "alpha", "dt"])
    Qq = file["weights"]["Qq"]
    assert task.Qq == (Qq if isinstance(Qq, list) else [Qq])
    # the model path is resolved against the task file's directory
    assert task.model == str(MJCF / "arm4.xml")


def test_paper_task_returns_a_copy():
    task = idmpc.paper_task()
    task.duration = 0.3
    assert idmpc.paper_task().duration != 0.3


@pytest.mark.parametrize("name", REACH_TASKS)
def test_reach_task_takes_defaults_from_arm_defaults(name):
    task = idmpc.load_task(str(MJCF / name))
    with open(MJCF / name) as f:
        file = json.load(f)
    defaults = idmpc.arm_defaults()
    assert task.source == str(MJCF / name)
    assert task.model == str(MJCF / file["model"])
    assert task.qref == pytest.approx(file["qref"])
    for field in ["formulation", "derivatives", "offset_free", "N", "kmax", "dt", "shooting"]:
        expected = file.get(field, file.get("cgmres", {}).get(field, getattr(defaults, field)))
        assert getattr(task, field) == expected, field


@pytest.mark.parametrize("name", ["paper_swingup.json"] + REACH_TASKS)
def test_dict_round_trip(name):
    task = idmpc.load_task(str(MJCF / name), base=idmpc.Task() if name.startswith("paper") else None)
    d = task.to_dict()
    assert d["schema"] == "idmpc-task/1"
    again = idmpc.task_from_dict(d)
    assert again.to_dict() == d
    # the dict is the task file's JSON: it survives a trip through a file
    assert idmpc.task_from_dict(json.loads(json.dumps(d))).to_dict() == d


def test_attributes_are_writable_and_reach_to_dict():
    task = idmpc.paper_task()
    task.duration = 0.3
    task.formulation = "fd"
    task.qref = np.array([0.1, 0.2, 0.3, 0.4])
    task.Qq = []  # "auto"
    task.N = 10
    task.q0_rule, task.q0 = "", [0.0, 0.1, 0.2, 0.3]
    d = task.to_dict()
    assert d["duration"] == 0.3 and d["formulation"] == "fd"
    assert d["qref"] == [0.1, 0.2, 0.3, 0.4]
    assert d["weights"]["Qq"] == "auto"
    assert d["cgmres"]["N"] == 10
    assert d["q0"] == [0.0, 0.1, 0.2, 0.3]


def test_task_from_dict_over_a_base():
    paper = idmpc.paper_task()
    task = idmpc.task_from_dict({"duration": 0.3, "cgmres": {"N": 10}, "qref": np.zeros(4)}, base=paper)
    assert task.duration == 0.3 and task.N == 10 and task.qref == [0.0] * 4
    assert task.kmax == paper.kmax and task.formulation == paper.formulation
    # without a base: the defaults for real arms
    assert idmpc.task_from_dict({}).to_dict() == idmpc.arm_defaults().to_dict()


def test_copies_are_independent():
    task = idmpc.paper_task()
    for other in [copy.copy(task), copy.deepcopy(task), idmpc.Task(task)]:
        other.duration = 0.3
        assert task.duration == idmpc.paper_task().duration


@pytest.mark.parametrize("d,message", [
    ({"durtion": 1}, "task dict: unknown field 'durtion'"),
    ({"duration": "long"}, "task dict: field 'duration': expected a number, got \"long\""),
    ({"cgmres": {"N": 2.5}}, "task dict, 'cgmres': field 'N': expected an integer, got 2.5"),
    ({"q0": "upright"}, "task dict: field 'q0': expected a list of joint positions, \"swingup\" or \"home\", got \"upright\""),
])
def test_bad_dict_is_a_value_error_with_the_cpp_message(d, message):
    with pytest.raises(ValueError) as e:
        idmpc.task_from_dict(d)
    assert str(e.value) == message


def test_non_finite_value_is_a_value_error():
    with pytest.raises(ValueError):
        idmpc.task_from_dict({"duration": float("nan")})


def test_missing_task_file_is_a_value_error(tmp_path):
    path = tmp_path / "none.json"
    with pytest.raises(ValueError) as e:
        idmpc.load_task(str(path))
    assert str(e.value) == f"task file '{path}': does not exist"


def test_bad_task_file_names_file_and_field(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"model": "arm4.xml", "weights": {"Qz": 1}}')
    with pytest.raises(ValueError) as e:
        idmpc.load_task(str(path))
    assert str(e.value) == f"task file '{path}', 'weights': unknown field 'Qz'"


# each attribute and where the task file's JSON keeps it
FIELDS = {
    "description": ("description",), "model": ("model",), "qref": ("qref",), "duration": ("duration",),
    "formulation": ("formulation",), "derivatives": ("derivatives",), "simd_stages": ("simd_stages",),
    "direct_torque": ("direct_torque",), "actuate_every_joint": ("actuate_every_joint",),
    "offset_free": ("offset_free",), "observer_time_constant": ("observer_time_constant",),
    "reach_tolerance": ("reach_tolerance",), "Qq": ("weights", "Qq"), "Qv": ("weights", "Qv"),
    "Qa": ("weights", "Qa"), "R": ("weights", "R"), "Qa_fallback": ("weights", "Qa_fallback"),
    "N": ("cgmres", "N"), "kmax": ("cgmres", "kmax"), "Tf": ("cgmres", "Tf"), "alpha": ("cgmres", "alpha"),
    "dt": ("cgmres", "dt"), "zeta": ("cgmres", "zeta"), "h": ("cgmres", "h"),
    "init_full_horizon": ("cgmres", "init_full_horizon"), "shooting": ("cgmres", "shooting"),
    "products": ("cgmres", "products"),
}


@pytest.mark.parametrize("name", ["paper_swingup.json"] + REACH_TASKS)
def test_each_attribute_is_its_own_field(name):
    task = idmpc.load_task(str(MJCF / name), base=idmpc.Task() if name.startswith("paper") else None)
    d = task.to_dict()
    for attribute, keys in FIELDS.items():
        value = d
        for key in keys:
            value = value[key]
        if value == "auto":
            value = 0 if attribute == "kmax" else []  # kmax 0: "auto"
        if isinstance(getattr(task, attribute), list) and not isinstance(value, list):
            value = [value]
        assert getattr(task, attribute) == value, attribute
    # a value written to each attribute lands in its field alone
    for i, (attribute, keys) in enumerate(FIELDS.items()):
        if isinstance(getattr(task, attribute), float):
            changed = idmpc.Task(task)
            setattr(changed, attribute, 1000.0 + i)
            after = changed.to_dict()
            value = after
            for key in keys:
                value = value[key]
            assert value == 1000.0 + i, attribute
            assert json.dumps(after).count(str(1000.0 + i)) == 1, attribute


def test_a_held_gripper_is_outside_the_controllers_coordinates():
    """The Panda with its hand: the controller and the plant's q have the arm's 7 joints, the
    plant's whole qpos also the two fingers, held open by their servo."""
    task = idmpc.load_task(str(MJCF / "panda_hand_reach.json"))
    task.duration = 0.2
    run = idmpc.TaskRun(task)
    result = run.run()
    assert run.plant.nv == 7
    assert run.plant.q.shape == (7,)
    assert run.plant.full_q.shape == (9,)
    assert np.allclose(run.plant.full_q[7:], 0.04, atol=1e-3)
    assert result["summary"]["held_joints"] == ["finger_joint1", "finger_joint2"]
