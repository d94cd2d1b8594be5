"""The dynamics kernels through the module: against each other, against central differences of
rnea and aba, and the errors for wrong sizes and bad model files."""

import numpy as np
import pytest

import idmpc
from conftest import random_state

SEEDS = [0, 1, 2]
# rnea and aba are each other's inverse up to the rounding of an n x n solve on unit-size data
INVERSE_TOL = 1e-9
# central differences with step h = 1e-6: truncation O(h^2 |d3|) and rounding O(eps/h) ~ 1e-10
# relative to the largest entry; 1e-6 leaves a margin of 100 on the panda's worst entry
FD_STEP = 1e-6
FD_TOL = 1e-6


def central_difference(f, x):
    """Columns (f(x + h e_j) - f(x - h e_j)) / 2h."""
    return np.column_stack([(f(x + FD_STEP * e) - f(x - FD_STEP * e)) / (2 * FD_STEP) for e in np.eye(x.size)])


def assert_close(actual, expected, tol, what):
    scale = max(1.0, np.abs(expected).max())
    err = np.abs(actual - expected).max()
    assert err <= tol * scale, f"{what}: max error {err:.3e} > {tol:.1e} x {scale:.3e}"


def test_model_attributes(model):
    assert model.n == len(model.joint_names) == len(model.parent) == len(model.joint_types)
    assert model.parent[0] == -1
    assert all(p < i for i, p in enumerate(model.parent))
    np.testing.assert_allclose(model.gravity, [0.0, 0.0, -9.81])
    for name in ["q_ref", "armature", "damping", "stiffness", "q_spring", "friction", "friction_velocity"]:
        assert getattr(model, name).shape == (model.n,), name
    assert "n = %d" % model.n in repr(model)


def test_arm4_is_the_papers_arm(arm4):
    assert arm4.n == 4
    assert set(arm4.joint_types) == {"revolute"}


@pytest.mark.parametrize("seed", SEEDS)
def test_aba_inverts_rnea(model, seed):
    q, v, a = random_state(model.n, seed)
    tau = idmpc.rnea(model, q, v, a)
    assert tau.shape == (model.n,) and tau.dtype == np.float64
    assert_close(idmpc.aba(model, q, v, tau), a, INVERSE_TOL, f"aba(rnea(a)) seed {seed}")
    assert_close(idmpc.rnea(model, q, v, idmpc.aba(model, q, v, a)), a, INVERSE_TOL, f"rnea(aba(tau)) seed {seed}")


@pytest.mark.parametrize("seed", SEEDS)
def test_crba_is_the_derivative_of_rnea_in_a(model, seed):
    q, v, _ = random_state(model.n, seed)
    M = idmpc.crba(model, q)
    assert M.shape == (model.n, model.n)
    np.testing.assert_array_equal(M, M.T)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    # rnea is affine in a: its columns minus the bias are M's columns, at any v
    bias = idmpc.rnea(model, q, v, np.zeros(model.n))
    columns = np.column_stack([idmpc.rnea(model, q, v, e) - bias for e in np.eye(model.n)])
    assert_close(columns, M, INVERSE_TOL, f"rnea columns seed {seed}")
    # and M[i, j] is M's entry (i, j): the layout survives the conversion to numpy
    assert_close(M @ np.arange(model.n), idmpc.rnea(model, q, v, np.arange(model.n)) - bias, INVERSE_TOL, "M a")


@pytest.mark.parametrize("seed", SEEDS)
def test_rnea_derivatives_match_central_differences(model, seed):
    q, v, a = random_state(model.n, seed)
    dtau_dq, dtau_dv, M = idmpc.rnea_derivatives(model, q, v, a)
    assert_close(dtau_dq, central_difference(lambda x: idmpc.rnea(model, x, v, a), q), FD_TOL, f"dtau_dq seed {seed}")
    assert_close(dtau_dv, central_difference(lambda x: idmpc.rnea(model, q, x, a), v), FD_TOL, f"dtau_dv seed {seed}")
    assert_close(M, idmpc.crba(model, q), INVERSE_TOL, f"M seed {seed}")


@pytest.mark.parametrize("seed", SEEDS)
def test_aba_derivatives_match_central_differences(model, seed):
    q, v, tau = random_state(model.n, seed)
    da_dq, da_dv, Minv = idmpc.aba_derivatives(model, q, v, tau)
    assert_close(da_dq, central_difference(lambda x: idmpc.aba(model, x, v, tau), q), FD_TOL, f"da_dq seed {seed}")
    assert_close(da_dv, central_difference(lambda x: idmpc.aba(model, q, x, tau), v), FD_TOL, f"da_dv seed {seed}")
    assert_close(Minv @ idmpc.crba(model, q), np.eye(model.n), INVERSE_TOL, f"Minv M seed {seed}")
    # ABA's derivatives are -M^-1 times RNEA's at the ABA result
    a = idmpc.aba(model, q, v, tau)
    dtau_dq, dtau_dv, _ = idmpc.rnea_derivatives(model, q, v, a)
    assert_close(da_dq, -Minv @ dtau_dq, INVERSE_TOL, f"da_dq = -Minv dtau_dq seed {seed}")


def test_inputs_may_be_lists_and_other_dtypes(arm4):
    q = [0.1, 0.2, 0.3, 0.4]
    expected = idmpc.rnea(arm4, np.array(q), np.zeros(4), np.zeros(4))
    np.testing.assert_array_equal(idmpc.rnea(arm4, q, [0, 0, 0, 0], np.zeros(4, dtype=np.float32)), expected)
    # a strided view is read with its strides
    wide = np.zeros((4, 2))
    wide[:, 0] = q
    np.testing.assert_array_equal(idmpc.rnea(arm4, wide[:, 0], np.zeros(4), np.zeros(4)), expected)


KERNELS = {
    "rnea": ["q", "v", "a"],
    "aba": ["q", "v", "tau"],
    "crba": ["q"],
    "rnea_derivatives": ["q", "v", "a"],
    "aba_derivatives": ["q", "v", "tau"],
}


@pytest.mark.parametrize("kernel,argument", [(k, a) for k, args in KERNELS.items() for a in args])
def test_wrong_size_is_a_value_error_naming_the_argument(arm4, kernel, argument):
    args = {name: np.zeros(4) for name in KERNELS[kernel]}
    args[argument] = np.zeros(3)
    with pytest.raises(ValueError) as e:
        getattr(idmpc, kernel)(arm4, *args.values())
    assert str(e.value) == f"{kernel}: {argument} has 3 entries, expected n = 4"


def test_missing_model_file_is_a_runtime_error(tmp_path):
    path = tmp_path / "missing.xml"
    with pytest.raises(RuntimeError, match="missing.xml") as e:
        idmpc.load_model(str(path))
    assert "\n" not in str(e.value)


def test_malformed_model_file_is_a_runtime_error(tmp_path):
    path = tmp_path / "broken.xml"
    path.write_text("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(RuntimeError, match="broken.xml"):
        idmpc.load_model(str(path))


BALL_JOINT = """<mujoco><worldbody><body name="b"><joint name="ball" type="ball"/>
<geom type="sphere" size="0.1"/></body></worldbody></mujoco>"""


def test_unsupported_model_is_a_value_error_naming_the_joint(tmp_path):
    path = tmp_path / "ball.xml"
    path.write_text(BALL_JOINT)
    with pytest.raises(ValueError, match="ball") as e:
        idmpc.load_model(str(path))
    assert "\n" not in str(e.value)


UNDER_ACTUATED = """<mujoco><worldbody><body name="b"><joint name="j1" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.05"/>
<body pos="0 0 -0.5"><joint name="j2" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.05"/>
</body></body></worldbody><actuator><motor joint="j1"/></actuator></mujoco>"""


def test_direct_torque_options_reach_the_import(tmp_path):
    path = tmp_path / "two.xml"
    path.write_text(UNDER_ACTUATED)
    # without the confirmation j2 stays passive (an under-actuated model)
    assert idmpc.load_model(str(path)).unactuated_joints == [1]
    assert idmpc.load_model(str(path), direct_torque=True).unactuated_joints == [1]
    model = idmpc.load_model(str(path), direct_torque=True, actuate_every_joint=True)
    assert model.unactuated_joints == []
    assert model.joint_names == ["j1", "j2"]
