"""One modal basis on the physical DOFs (issue 22, item 3): when the families couple (elements rotated out of the
straight axis by the assembler, :mod:`drillstring.fem.geometry`) the reduced model is built on the modes of the
whole string, every physical quantity reads every column and the damping is one full block; integrated in time
it converges to the full finite-element model (the exact solution of the same linear M, C, K and load by a matrix
exponential) as modes are added."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.integrate import solve_ivp

from drillstring.dynamics.rom import reduced_model
from drillstring.fem.assembly import structural_matrices
from drillstring.fem.build import section_fluid_coefficients, stabilizers
from drillstring.fem.dofs import THETA_X, U, V, W, dof
from drillstring.fem.geometry import centreline_directions, direction_cosines, rotate_element_matrices
from drillstring.fem.element import element_stiffness
from drillstring.forces.contact import case_contact
from drillstring.forces.off_bottom import OffBottom
from drillstring.modal import build_linear_system, coupled_dofs, family_coupling
from drillstring.statics import case_static_state

RAYLEIGH = (0.05, 1e-4)  # α [1/s], β [s]: the same structural damping in both models


def test_direction_cosines_of_the_straight_axis_are_the_identity(drill_pipe):
    np.testing.assert_array_equal(direction_cosines(np.array([[1.0, 0.0, 0.0]])), np.eye(3)[None])
    tangent = np.array([[0.6, 0.48, 0.64]])
    r = direction_cosines(tangent)[0]
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(r) == pytest.approx(1.0)
    np.testing.assert_allclose(r[0], tangent[0])
    # an element along the tangent: its stiffness has the local one's eigenvalues, and a rigid translation in any
    # global direction and a rigid rotation about its own axis cost no energy
    local = element_stiffness(drill_pipe, 9.0)
    rotated = rotate_element_matrices(local[None], r[None])[0]
    np.testing.assert_allclose(np.linalg.eigvalsh(rotated), np.linalg.eigvalsh(local), atol=1e-6 * np.abs(local).max())
    for axis in range(3):
        translation = np.tile(np.eye(3)[axis], 4) * np.repeat([1.0, 0.0, 1.0, 0.0], 3)
        assert np.abs(rotated @ translation).max() < 1e-6 * np.abs(local).max()
    spin = np.concatenate([np.zeros(3), r[0], np.zeros(3), r[0]])
    assert np.abs(rotated @ spin).max() < 1e-6 * np.abs(local).max()
    with pytest.raises(ValueError, match="tangents"):
        direction_cosines(np.array([[2.0, 0.0, 0.0]]))


def test_the_identity_rotation_assembles_the_straight_string_bit_for_bit(small_case):
    mesh = case_static_state(small_case).mesh
    plain = structural_matrices(mesh)
    turned = structural_matrices(mesh, np.broadcast_to(np.eye(3), (mesh.n_nodes - 1, 3, 3)))
    for a, b in zip(plain, turned):
        assert (a != b).nnz == 0


@pytest.fixture(scope="module")
def bent(reference_case):
    """The reference string on a 50 m mesh whose lower third builds up 3° per element while turning 20° in azimuth
    per element (its centreline's chords give each element's direction), prestressed by the straight string's
    static axial force, with its mud (the fluid's non-proportional damping)."""
    case = reference_case.model_copy(update={"mesh": reference_case.mesh.model_copy(
        update={"max_element_length": 50.0})})
    static = case_static_state(case)
    mesh = static.mesh
    n_el = mesh.n_nodes - 1
    build = 2 * n_el // 3
    inclination = np.radians(3.0) * np.maximum(np.arange(n_el) - build + 1, 0)
    azimuth = np.radians(20.0) * np.maximum(np.arange(n_el) - build + 1, 0)
    tangents = np.stack([np.cos(inclination), np.sin(inclination) * np.cos(azimuth),
                         np.sin(inclination) * np.sin(azimuth)], axis=1)
    points = np.vstack([np.zeros(3), np.cumsum(tangents * mesh.element_lengths[:, None], axis=0)])
    rotations = direction_cosines(centreline_directions(points))
    system = build_linear_system(mesh, static, stabilizers(case), section_fluid_coefficients(case, mesh),
                                 rotations=rotations)
    return case, static, system, build


def _model(bent, count, correction="none", **overrides):
    case, static, system, _ = bent
    options = dict(axial_modes=count - 1, torsional_modes=0, lateral_modes=0, modal_damping_ratio=0.0,
                   rigid_axial_damping=0.0, top_speed=0.0, bit_rock=OffBottom(), contact=case_contact(case),
                   borehole_diameter=1000.0, damping_basis="constrained", rayleigh=RAYLEIGH,
                   truncation_correction=correction)
    options.update(overrides)
    return reduced_model(static, system, **options)


def test_a_bent_string_couples_its_families_and_gets_one_basis(bent):
    case, static, system, _ = bent
    assert family_coupling(system) > 1e6  # [N/m]: the straight string's is exactly 0
    model = _model(bent, 17)
    assert model.coupled and model.family[0] == "rigid_axial" and set(model.family[1:]) == {"coupled"}
    n = model.size
    np.testing.assert_array_equal(model.blocks, [0, n] * 4)  # every quantity reads every column
    np.testing.assert_array_equal(model.case2_data.damping_blocks, [[0, n]])  # one full damping block
    off_diagonal = model.damping - np.diag(np.diag(model.damping))
    assert np.abs(off_diagonal).max() > 1e-3 * np.abs(np.diag(model.damping)).max()  # the mud's C_f
    # a load at the bit's u moves the lateral and torsional DOFs (the straight string's would not)
    bit = static.mesh.n_nodes - 1
    static_response = model.basis @ (model.bit_u / np.where(model.omega2 > 0, model.omega2, np.inf))
    assert np.abs(static_response[dof(np.arange(bit), V)]).max() > 0.0
    assert np.abs(static_response[dof(np.arange(bit), THETA_X)]).max() > 0.0
    y = np.random.default_rng(3).standard_normal(2 * n)
    np.testing.assert_allclose(model.rhs(0.3, y), model.rhs_reference(0.3, y), rtol=1e-12, atol=1e-9)


def test_the_reduced_bent_string_converges_to_the_full_finite_element_model_in_time(bent):
    """The weight-on-bit W applied at the bit's u at t = 0 to the string at rest (the off-bottom law: the kernels'
    bit force is W, the static bit reaction): the full model ``M q̈ + C q̇ + K q = W e_bit,u`` on the free DOFs,
    ``C = α M + β K + C_f``, solved exactly by the matrix exponential of the first-order system at 10 ms steps
    over 3 s; the reduced model's compiled right-hand side integrated by SciPy (DOP853, rtol 1e-10). The error
    is the largest mass-norm distance of the displacement fields over the run relative to the largest full
    displacement; measured 22 %, 4.8 %, 0.70 %, 0.43 % with 8, 16, 32, 64 modes; with the truncation correction
    (the static one at the bit's u and θx, on the coupled basis) 6.5 %, 2.2 %, 0.64 %, 0.24 %."""
    case, static, system, _ = bent
    mesh = static.mesh
    dofs = coupled_dofs(mesh)
    mass = system.mass[dofs][:, dofs].toarray()
    stiffness = system.stiffness[dofs][:, dofs].toarray()
    damping = RAYLEIGH[0] * mass + RAYLEIGH[1] * stiffness + system.fluid_damping[dofs][:, dofs].toarray()
    load = np.zeros(mesh.n_dofs)
    load[dof(mesh.n_nodes - 1, U)] = static.weight_on_bit
    n_f = len(dofs)
    inverse = np.linalg.inv(mass)
    first_order = np.zeros((2 * n_f + 1, 2 * n_f + 1))
    first_order[:n_f, n_f:2 * n_f] = np.eye(n_f)
    first_order[n_f:2 * n_f, :n_f] = -inverse @ stiffness
    first_order[n_f:2 * n_f, n_f:2 * n_f] = -inverse @ damping
    first_order[n_f:2 * n_f, -1] = inverse @ load[dofs]
    step, steps = 0.01, 300
    propagator = sla.expm(first_order * step)
    z = np.zeros(2 * n_f + 1)
    z[-1] = 1.0
    full = [z[:n_f].copy()]
    for _ in range(steps):
        z = propagator @ z
        full.append(z[:n_f].copy())
    full = np.array(full)
    times = step * np.arange(steps + 1)
    scale = np.sqrt(np.einsum("ti,ij,tj->t", full, mass, full).max())
    errors = {}
    for correction in ("none", "static"):
        for count in (8, 16, 32, 64):
            model = _model(bent, count, correction)
            solution = solve_ivp(model.rhs, (0.0, times[-1]), np.zeros(2 * model.size), t_eval=times,
                                 method="DOP853", rtol=1e-10, atol=1e-12)
            assert solution.success
            reduced = (model.basis[dofs] @ solution.y[:model.size]).T
            difference = reduced - full
            errors[correction, count] = np.sqrt(np.einsum("ti,ij,tj->t", difference, mass, difference).max()) / scale
    plain = [errors["none", c] for c in (8, 16, 32, 64)]
    corrected = [errors["static", c] for c in (8, 16, 32, 64)]
    assert all(b < a for a, b in zip(plain, plain[1:])), plain
    assert all(b < a for a, b in zip(corrected, corrected[1:])), corrected
    assert plain[0] > 0.1 and plain[-1] < 0.006  # 22 % down to 0.43 %
    assert all(c < p for c, p in zip(corrected, plain)), (corrected, plain)  # the correction helps at every size
    assert corrected[-1] < 0.003


@pytest.mark.parametrize("override, field", [({"nonlinear": "full"}, "nonlinear"),
                                             ({"top_speed": 1.0}, "top_speed"),
                                             ({"damping_basis": "free_free"}, "damping.basis")])
def test_what_a_coupled_basis_does_not_support_is_refused_by_name(bent, override, field):
    with pytest.raises(ValueError, match=field):
        _model(bent, 8, **override)
