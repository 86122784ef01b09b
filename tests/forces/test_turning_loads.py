"""Tests of the turning-loads component (mass imbalance and bow projected on the lateral modes)."""

import numpy as np
import pytest
import scipy.sparse as sp
from numba import njit

from drillstring.forces.excitation import TurningLoads
from drillstring.forces.turning_loads import TurningLoadData, case_turning_loads, turning_load, turning_load_data

N_DOFS, N_NODES, N_Y, N_Z = 18, 3, 4, 3


@pytest.fixture(scope="module")
def loads():
    rng = np.random.default_rng(7)
    # as in the model: y loads on the y DOFs (even rows here), z loads and z modes on the others
    y_rows = (np.arange(N_DOFS) % 2 == 0)[:, None]
    patterns = [sp.random(N_DOFS, 3, density=0.4, random_state=s).toarray() for s in (1, 2)]
    patterns = [sp.csc_matrix(patterns[0] * y_rows), sp.csc_matrix(patterns[1] * ~y_rows)]
    physical = TurningLoads(np.array([0, 2, 1], dtype=np.int64), np.array([0.3, -1.1, 2.0]),
                            np.array([True, False, True]), *patterns)
    shapes_y, shapes_z = rng.normal(size=(N_DOFS, N_Y)) * y_rows, rng.normal(size=(N_DOFS, N_Z)) * ~y_rows
    return physical, shapes_y, shapes_z, turning_load_data(physical, shapes_y, shapes_z)


def _state(rng):
    return rng.normal(size=N_NODES), 10.0 * rng.normal(size=N_NODES)


def test_evaluate_is_the_projection_of_the_physical_loads(loads):
    """Against the global load vector of :class:`TurningLoads` projected with the mode shapes."""
    physical, shapes_y, shapes_z, data = loads
    rotation, spin = _state(np.random.default_rng(1))
    global_force = physical.forces(rotation, spin)
    f_y, f_z = data.evaluate(rotation[data.node] + data.phase, spin[data.node])
    np.testing.assert_allclose(f_y, shapes_y.T @ global_force, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f_z, shapes_z.T @ global_force, rtol=1e-12, atol=1e-12)


def test_jacobian_matches_finite_differences(loads):
    data = loads[3]
    rng = np.random.default_rng(2)
    angle, speed = rng.normal(size=3), 10.0 * rng.normal(size=3)
    jac = data.jacobian(angle, speed)
    assert jac.shape == (N_Y + N_Z, 6)
    x = np.concatenate([angle, speed])
    fd = np.zeros_like(jac)
    for b in range(6):
        h = 1e-6 * max(1.0, abs(x[b]))
        hi, lo = x.copy(), x.copy()
        hi[b] += h
        lo[b] -= h
        forces_hi = np.concatenate(data.evaluate(hi[:3], hi[3:]))
        fd[:, b] = (forces_hi - np.concatenate(data.evaluate(lo[:3], lo[3:]))) / (2 * h)
    np.testing.assert_allclose(jac, fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())
    assert not jac[:, 3 + 1].any()  # the bow's entry does not depend on the speed
    assert jac[:, 3].any() and jac[:, 1].any()


@njit(cache=True)
def _compiled(data, angle, speed, out):
    for k in range(data.node.shape[0]):
        turning_load(data, k, angle[k], speed[k], out, 0, N_Y, N_Y, N_Y + N_Z)


def test_compiled_kernel_matches_the_reference(loads):
    data = loads[3]
    angle, speed = np.array([0.4, 2.5, -3.0]), np.array([12.0, -7.0, 0.5])
    out = np.ones(N_Y + N_Z)
    _compiled(data, angle, speed, out)
    np.testing.assert_allclose(out - 1.0, np.concatenate(data.evaluate(angle, speed)), rtol=1e-13, atol=1e-12)


def test_case_turning_loads_of_the_contact_case():
    from drillstring.case import load_case
    from drillstring.fem.build import case_mesh

    case = load_case("contact")
    loads = case_turning_loads(case, case_mesh(case))
    assert len(loads) > 0 and loads.speed_squared.all()  # a mass imbalance, no bow
    reference = load_case("reference")
    assert len(case_turning_loads(reference, case_mesh(reference))) == 0


def test_the_sources_are_registered_with_their_own_keys_and_one_from_outside_runs_compiled(coarse_case):
    """The mass imbalance and the bow are registered turning-load sources, each with its own keys; a rotating
    point force written here (no kernel of its own: the sources share one) runs through the compiled kernels and
    pushes the string at rest with ``F (cos(Ωt + φ) φ_v(i) + sin(Ωt + φ) φ_w(i))`` on the modal accelerations."""
    from dataclasses import dataclass, replace
    from typing import ClassVar

    from drillstring.case import Bow, ImbalanceKeys, Section
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.fem.dofs import V, W, dof
    from drillstring.forces.registry import TurningLoadSource, register, turning_load_source, turning_load_sources
    from drillstring.forces.turning_loads import MassImbalance, StressFreeBow

    assert turning_load_sources(package_only=True) == ("imbalance", "bow")
    assert turning_load_source("imbalance") is MassImbalance and MassImbalance.keys is ImbalanceKeys
    assert StressFreeBow.keys is Bow and set(ImbalanceKeys.model_fields) <= set(Section.model_fields)

    @register
    @dataclass(frozen=True)
    class RotatingPointForce(TurningLoadSource):
        name: ClassVar[str] = "rotating_point_force_test"
        node: int = 10
        force: float = 3e3  # [N]
        phase: float = 0.4  # [rad]

        def loads(self, mesh):
            pattern = lambda kind: sp.csc_matrix(([self.force], ([dof(self.node, kind)], [0])), shape=(mesh.n_dofs, 1))
            return TurningLoads(np.array([self.node]), np.array([self.phase]), np.array([False]), pattern(V),
                                pattern(W))

    plain = case_reduced_model(coarse_case, lateral_modes=5)
    source = RotatingPointForce()
    pushed = replace(plain, turning_loads=case_turning_loads(coarse_case, plain.static.mesh, sources=[source]))
    assert pushed.compiled  # the outside source needs no kernel of its own
    n, t, omega = plain.size, 0.8, plain.top_speed
    at_rest = np.zeros(2 * n)
    push = pushed.rhs(t, at_rest)[n:] - plain.rhs(t, at_rest)[n:]
    alpha = omega * t + source.phase
    expected = source.force * (np.cos(alpha) * pushed.phi_v[source.node] + np.sin(alpha) * pushed.phi_w[source.node])
    np.testing.assert_allclose(push, expected, rtol=1e-10, atol=1e-12 * np.abs(expected).max())
    assert np.abs(expected).max() > 0.0
    np.testing.assert_allclose(pushed.rhs(t, at_rest), pushed.rhs_reference(t, at_rest), rtol=1e-12, atol=1e-9)
