"""Shared fixtures: the shipped models and task files, found relative to this file."""

from pathlib import Path

import numpy as np
import pytest

import idmpc

MJCF = Path(__file__).resolve().parents[2] / "mjcf"


@pytest.fixture(scope="session")
def mjcf():
    return MJCF


@pytest.fixture(scope="session", params=["arm4.xml", "panda.xml"])
def model(request):
    """The paper's planar arm and a real arm (Franka Panda, 7 joints)."""
    return idmpc.load_model(str(MJCF / request.param))


@pytest.fixture(scope="session")
def arm4():
    return idmpc.load_model(str(MJCF / "arm4.xml"))


def random_state(n, seed):
    """(q, v, a) with entries in [-1, 1] from a seeded generator."""
    rng = np.random.default_rng(seed)
    return tuple(rng.uniform(-1.0, 1.0, n) for _ in range(3))
