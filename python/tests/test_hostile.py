"""Hostile inputs from Python: sizes and horizons that crashed the interpreter, a NaN in a task
dict, Ctrl-C during a long run, a failed debug check, and what the module says about itself
(__version__, the type stubs). Each is a Python exception with one line naming the problem, never
an abort. The cases that crashed run in a child interpreter, so that a crash fails its test only."""

import _thread
import math
import re
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

import idmpc
from conftest import MJCF

ROOT = Path(__file__).resolve().parents[2]


def child(code):
    """Runs code in a child interpreter with this module; (exit code, stdout + stderr)."""
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120)
    return r.returncode, r.stdout + r.stderr


@pytest.mark.parametrize("weight", ["[]", "[1.0, 2.0]"])
def test_a_frame_task_weight_of_the_wrong_size_raises(weight):
    code, out = child(f"""
        import idmpc
        task = idmpc.load_task("{MJCF / 'ur5e_circle.json'}")
        task.target = idmpc.FrameTask("tip", position_weight={weight})
        task.duration = 0.01
        try:
            idmpc.TaskRun(task)
        except ValueError as e:
            print("ValueError:", e)
        """)
    assert code == 0, out
    assert "ValueError: target.weights.position has" in out and "expected 1 or 3" in out, out


@pytest.mark.parametrize("field, value", [("position", "[0.1, 0.2]"), ("orientation", "[1.0, 0.0, 0.0]")])
def test_a_frame_task_pose_of_the_wrong_size_raises(field, value):
    code, out = child(f"""
        import idmpc
        task = idmpc.load_task("{MJCF / 'ur5e_circle.json'}")
        task.reference = None
        task.target = idmpc.FrameTask("tip", {field}={value})
        try:
            idmpc.TaskRun(task)
        except ValueError as e:
            print("ValueError:", e)
        """)
    assert code == 0, out
    assert f"ValueError: target.{field} has" in out, out


@pytest.mark.parametrize("N", [0, 10001, 2**31 - 1])
def test_a_controller_horizon_beyond_its_limit_raises(N):
    code, out = child(f"""
        import idmpc
        model = idmpc.load_model("{MJCF / 'arm4.xml'}")
        s = idmpc.ControllerSettings()
        s.weights.Qq = [1] * 4
        s.weights.Qv = [0.1] * 4
        s.weights.R = [1e-4] * 4
        s.q_ref = [0] * 4
        s.N = {N}
        try:
            idmpc.Controller(model, s)
        except ValueError as e:
            print("ValueError:", e)
        """)
    assert code == 0, out
    assert f"ValueError: controller settings: N must be from 1 to 10000 horizon stages, got {N}" in out, out


@pytest.mark.parametrize("d, field", [({"duration": math.nan}, "duration"),
                                      ({"cgmres": {"Tf": math.inf}}, "cgmres.Tf"),
                                      ({"qref": [0.0, -math.inf]}, "qref[1]")])
def test_a_non_finite_number_in_a_task_dict_names_its_field(d, field):
    with pytest.raises(ValueError, match=re.escape(f"task dict: field '{field}': expected a finite number, got ")):
        idmpc.task_from_dict(d)


def test_a_non_finite_reference_names_its_field():
    with pytest.raises(ValueError, match=re.escape("field 'radius': expected a finite number, got nan")):
        idmpc.trajectory_from_dict({"shape": "circle", "radius": math.nan, "frequency": 1}, [0.3, 0.1, 0.5])


def test_a_circle_that_would_sample_nan_raises():
    with pytest.raises(ValueError, match="frequency must be at most"):
        idmpc.CircleTrajectory([0, 0, 0], [1, 0, 0], 0.05, 1e308, [0, 0, 1])
    with pytest.raises(ValueError, match="'ramp'"):
        idmpc.trajectory_from_dict({"shape": "circle", "radius": 0.05, "frequency": 1, "ramp": 1e308},
                                   [0.3, 0.1, 0.5])


def test_ctrl_c_interrupts_a_long_run():
    task = idmpc.paper_task()
    task.duration = 600  # minutes of computing: it must end at the signal, not at its end
    run = idmpc.TaskRun(task)
    timer = threading.Timer(0.5, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run.run()
    finally:
        timer.cancel()
    assert time.monotonic() - start < 10


def test_ctrl_c_interrupts_a_long_start():
    # a start of 100,000 Riccati iterations on the Panda (tens of seconds): Controller.initialize,
    # and the same start inside TaskRun.run, end at the signal
    task = idmpc.load_task(str(MJCF / "panda_reach.json"))
    task.solver = "riccati"
    task.riccati.init_iterations = 100000
    task.riccati.init_tolerance = 0
    run = idmpc.TaskRun(task)
    for call in (lambda: run.controller.initialize(run.q0, [0.0] * run.n), run.run):
        timer = threading.Timer(0.5, _thread.interrupt_main)
        start = time.monotonic()
        timer.start()
        try:
            with pytest.raises(KeyboardInterrupt):
                call()
        finally:
            timer.cancel()
        assert time.monotonic() - start < 5


def test_without_numpy_the_import_error_says_what_to_do():
    # an interpreter that cannot import numpy (here: made so), as a python3 first on PATH may be
    code, out = child("""
        import sys
        sys.modules["numpy"] = None
        import idmpc
        """)
    assert code != 0
    assert "ImportError: idmpc needs numpy, which this interpreter (" in out, out
    assert "the interpreter idmpc was built for" in out, out


def test_a_failed_debug_check_raises_instead_of_aborting():
    code, out = child("""
        import idmpc
        try:
            idmpc._fail_debug_check()
        except AssertionError as e:
            print(type(e).__name__, e)
        """)
    assert code == 0, out
    assert "DebugCheckError" in out and "idmpc debug check failed: a check failed on request" in out, out
    assert issubclass(idmpc.DebugCheckError, AssertionError)


def test_the_version_is_the_projects():
    cmake = (ROOT / "CMakeLists.txt").read_text()
    version = re.search(r"project\(idmpc VERSION ([0-9.]+)", cmake).group(1)
    assert idmpc.__version__ == version


def stub_names(tree):
    """{name: set of member names} of the stub's classes, and "" for its module-level names."""
    import ast
    names = {"": set()}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[""].add(node.name)
            members = names.setdefault(node.name, set())
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AnnAssign)):
                    members.add(item.name if isinstance(item, ast.FunctionDef) else item.target.id)
        elif isinstance(node, ast.FunctionDef):
            names[""].add(node.name)
        elif isinstance(node, ast.AnnAssign):
            names[""].add(node.target.id)
    return names


def test_the_type_stubs_name_what_the_module_has():
    """The stubs beside the module (build tree and install) parse and list exactly its names."""
    import ast
    stub = Path(idmpc.__file__).with_name("idmpc.pyi")
    assert stub.is_file(), f"no type stubs beside {idmpc.__file__}"
    names = stub_names(ast.parse(stub.read_text()))
    module = {k for k in dir(idmpc) if not k.startswith("__") or k == "__version__"}
    assert names[""] == module
    for cls in (getattr(idmpc, k) for k in module):
        if not isinstance(cls, type) or issubclass(cls, BaseException):
            continue
        members = {k for k in cls.__dict__ if not k.startswith("_") or k in ("__init__", "__copy__", "__deepcopy__")}
        if "__init__" not in names[cls.__name__]:
            # a class only the module makes (Model, Plant): no constructor for Python
            with pytest.raises(TypeError, match="No constructor defined"):
                cls()
            members.discard("__init__")
        assert names[cls.__name__] == members, cls.__name__


def test_attributes_and_methods_are_one_kind_each():
    """What an object has is an attribute (no call), what it does a method: across the classes."""
    run = idmpc.TaskRun(idmpc.load_task(str(MJCF / "lite6_reach.json")))
    c, plant = run.controller, run.plant
    assert c.n == run.n == plant.nv == run.model.n
    assert c.torque_lower.tolist() == run.torque_lower.tolist()
    assert c.dt == pytest.approx(plant.timestep * plant.substeps)
    assert isinstance(c.failure, str) and isinstance(plant.time, float)
    for name in ("initialize", "update", "set_target", "set_frame_target", "set_torque_limits",
                 "set_disturbance_observer"):
        assert callable(getattr(c, name)), name
