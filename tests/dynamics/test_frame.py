"""Kinematics in one place (docs/model.md §8): every station's spin is computed by the frame
(:mod:`drillstring.dynamics.reduced.frame`) and the laws read it through their contexts."""

import re
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from drillstring.dynamics.reduced.frame import (
    bit_axial_motion,
    frame_speed,
    lateral_displacements,
    station_lateral_velocity,
    station_spin,
)
from drillstring.dynamics.reduced.terms import _bit_rock
from drillstring.dynamics.rom import case_reduced_model
from drillstring.forces.protocol import BitContext

SOURCE = Path(__file__).resolve().parents[2] / "src" / "drillstring"


@njit
def _spin(d, t, y, node, phase):
    return station_spin(d, t, y, node, phase)


@njit
def _frame_speed(d):
    return frame_speed(d)


@njit
def _translation(d, y, node, v, w):
    lateral_displacements(d, y, v, w)
    return bit_axial_motion(d, y), station_lateral_velocity(d, y, node)


@njit
def _bit(d, t, y):
    return _bit_rock(d, t, y)


@pytest.fixture(scope="module")
def spinning(coarse_case):
    """The coarse reference string spun at an imposed 12 rad/s (the frame turns) and a state of chosen motion."""
    case = coarse_case.model_copy(update={"operation": coarse_case.operation.model_copy(update={"top_speed": 12.0})})
    model = case_reduced_model(case, lateral_modes=6)
    rng = np.random.default_rng(7)
    n = model.size
    y = np.concatenate([1e-3 * rng.standard_normal(n), 1e-2 * rng.standard_normal(n)])
    return model, y


def test_a_stations_spin_is_the_frames_map_of_the_state(spinning):
    model, y = spinning
    n, t = model.size, 0.37
    d = model.case2_data
    assert model.base_speed == 12.0 and _frame_speed(d) == 12.0
    for node in (0, model.phi_tx.shape[0] // 2, model.phi_tx.shape[0] - 1):
        for phase in (0.0, 0.8):
            angle, speed = _spin(d, t, y, node, phase)
            assert angle == pytest.approx(12.0 * t + phase + model.phi_tx[node] @ y[:n], rel=1e-12)
            assert speed == pytest.approx(12.0 + model.phi_tx[node] @ y[n:], rel=1e-12)


def test_a_stations_translation_is_the_frames_map_of_the_state(spinning):
    model, y = spinning
    n = model.size
    nodes = model.phi_v.shape[0]
    v, w = np.empty(nodes), np.empty(nodes)
    node = nodes // 2
    (position, velocity), (v_dot, w_dot) = _translation(model.case2_data, y, node, v, w)
    assert (position, velocity) == pytest.approx((model.bit_u @ y[:n], model.bit_u @ y[n:]), rel=1e-12)
    np.testing.assert_allclose(v, model.phi_v @ y[:n], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(w, model.phi_w @ y[:n], rtol=1e-12, atol=1e-18)
    assert (v_dot, w_dot) == pytest.approx((model.phi_v[node] @ y[n:], model.phi_w[node] @ y[n:]), rel=1e-12)


def test_the_bit_law_reads_the_motion_of_the_bit_through_its_context(spinning):
    model, y = spinning
    n, t = model.size, 0.37
    d = model.case2_data
    force, torque, _, position, velocity, speed = _bit(d, t, y)
    assert speed == _spin(d, t, y, model.phi_tx.shape[0] - 1, 0.0)[1]  # the frame's, bit for bit
    # the law given a context computed by hand from the chosen motion returns that motion's force
    by_hand = BitContext(t, model.bit_u @ y[:n], 12.0 * t + model.bit_t @ y[:n], model.bit_u @ y[n:],
                         12.0 + model.bit_t @ y[n:], 0.0, model.weight_on_bit)
    assert (position, velocity, speed) == pytest.approx(tuple(by_hand[1:2] + by_hand[3:5]), rel=1e-12)
    expected_force, expected_torque = model.bit_rock.evaluate_at(by_hand)
    assert (force, torque) == pytest.approx((float(expected_force), float(expected_torque)), rel=1e-9)


def test_one_place_computes_a_stations_spin():
    """A source-level supplement: outside the frame, no compiled kernel of the reduced model or law reads the
    frame's rotation Ω (``top_speed`` of the kernel data) to build a station's angle or spin."""
    readers = []
    for path in sorted([*(SOURCE / "dynamics" / "reduced").glob("*.py"), *(SOURCE / "forces").glob("*.py")]):
        if path.name == "frame.py":
            continue
        if re.search(r"\bd\.top_speed\b|\.rhs\.top_speed\b", path.read_text()):
            readers.append(path.name)
    assert readers == []
