"""The static correction on the well basis (reduced_model.truncation_correction = "static" with
lateral_basis = "well"): residual-flexibility attachment modes for unit loads at the bit (along its tangent,
about it) and the top (along its tangent) on the modes about the stiff string's static state
(:func:`drillstring.well.well_modes.quota_modes`, docs/stiff_string.md, The well basis)."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from drillstring.dynamics.reduced.build import friction_load_patterns
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.fem.dofs import THETA_X, U, dof
from drillstring.modal import coupled_dofs
from tests.well.well_cases import deviated_for_well_basis


@pytest.fixture(scope="module")
def deviated():
    """``deviated`` on a 60 m mesh (330 free DOFs), the constrained damping and the start on bottom."""
    return deviated_for_well_basis(60.0)


def _model(case, correction: str, axial: int, torsional: int, lateral: int):
    return case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(update={
        "lateral_basis": "well", "truncation_correction": correction, "axial_modes": axial,
        "torsional_modes": torsional, "lateral_modes": lateral})}))


def test_the_corrected_well_basis_gives_the_static_response_to_the_bits_and_tops_loads(deviated):
    """A unit load at the bit (along its tangent, about it) or at the top (along its tangent): the elastic columns'
    static response ``Φ Ω⁻² Φᵀ f`` is the inertia-relief solution of the whole system, the bordered
    ``[[K, M s], [sᵀ M, 0]] [x, λ] = [f, 0]`` (``s`` the slide along the path; an independent sparse solve), over
    every free DOF: to 1e-6 of its largest entry with the correction (measured 6.1e-8, 6.3e-12, 2.5e-8: the
    grounded stiffness's condition number, 8.2e8, times the machine epsilon is 1.8e-7), off by 13 %, 1.2 % and
    25 % without. The same for the along-string friction's two load patterns (μ N along the string at the 45
    resting nodes, their torques about it: :func:`~drillstring.dynamics.reduced.build.friction_load_patterns`):
    6.0e-7 and 6.9e-12 with the correction, 41 % and 0.65 % without. The basis stays M-orthonormal and
    diagonalises K."""
    plain, corrected = _model(deviated, "none", 3, 3, 4), _model(deviated, "static", 3, 3, 4)
    # the top's θx is held (an imposed top speed); the along-string friction's two load patterns add one each
    assert corrected.modes.coupled.attachments == 5
    assert int(corrected.residual_columns.sum()) == 5 and not plain.residual_columns.any()
    np.testing.assert_array_equal(corrected.basis[:, :-5], plain.basis)  # the kept modes are left as they are
    system = corrected.system
    dofs = coupled_dofs(system.mesh)
    k, m = system.stiffness[dofs][:, dofs], system.mass[dofs][:, dofs]
    phi = corrected.basis[dofs]
    np.testing.assert_allclose(phi.T @ (m @ phi), np.eye(phi.shape[1]), atol=1e-8)
    elastic = phi[:, 1:].T @ (k @ phi[:, 1:])
    np.testing.assert_allclose(elastic, np.diag(corrected.angular_frequencies[1:] ** 2),
                               atol=1e-10 * np.abs(elastic).max())
    ms = m @ phi[:, 0]
    bordered = sp.bmat([[k, sp.csr_matrix(ms[:, None])], [sp.csr_matrix(ms[None, :]), None]]).tocsc()
    bit = system.mesh.n_nodes - 1
    loads = np.zeros((system.mesh.n_dofs, 3))
    loads[[dof(bit, U), dof(bit, THETA_X), dof(0, U)], [0, 1, 2]] = 1.0
    patterns = friction_load_patterns(corrected.string_friction, corrected.friction_stations, corrected.top_speed,
                                      system.mesh.n_dofs)
    for index, load in enumerate(np.hstack([loads, patterns]).T):
        exact = spla.spsolve(bordered, np.append(load[dofs], 0.0))[:-1]
        error = {}
        for name, model in (("plain", plain), ("corrected", corrected)):
            columns = model.basis[dofs][:, 1:]
            response = columns @ ((columns.T @ load[dofs]) / model.angular_frequencies[1:] ** 2)
            error[name] = np.abs(response - exact).max() / np.abs(exact).max()
        assert error["corrected"] < 1e-6, index
        assert error["plain"] > 5e-3, index


def test_the_correction_converges_a_short_run_on_the_well_basis(deviated):
    """2 s of drilling from the start on bottom, against the plain basis of 40 + 40 + 2·60 modes: 3 + 3 + 2·4
    modes end 0.035 rad/s off the bit speed, 0.79 N off the force on bit (means of the last 0.2 s; 79.3 kN) and
    496 N·m off the surface torque, with the correction 0.0025 rad/s, 0.21 N and 1.8 N·m; the RMS errors over the
    run, of each signal's RMS: bit speed 4.3 %, 2.4 % with it, surface torque 2.4 %, 0.21 % with it. (With the
    bit's and top's attachment modes alone, without the friction's load patterns: 0.0016 rad/s, 0.32 N, 326 N·m;
    RMS 3.0 % and 1.6 %. The force on bit's RMS error does not improve: 0.25 %, 0.29 % with it; the attachment
    modes' ω̃, 11-15 rad/s, lie among the lateral modes the quota leaves out.)"""
    runs = {}
    for name, (correction, axial, torsional, lateral) in {"reference": ("none", 40, 40, 60), "plain": ("none", 3, 3, 4),
                                                          "corrected": ("static", 3, 3, 4)}.items():
        result = simulate_model(_model(deviated, correction, axial, torsional, lateral), t_end=2.0, output_step=0.01)
        runs[name] = {k: np.asarray(result.observables[k]) for k in ("bit_speed", "force_on_bit", "surface_torque")}
    reference = runs["reference"]

    def end_error(run, key):
        return abs(run[key][-20:].mean() - reference[key][-20:].mean())

    def rms_error(run, key):
        return np.sqrt(np.mean((run[key] - reference[key]) ** 2) / np.mean(reference[key] ** 2))

    assert end_error(runs["corrected"], "bit_speed") < 0.1 * end_error(runs["plain"], "bit_speed")
    assert end_error(runs["corrected"], "force_on_bit") < 0.6 * end_error(runs["plain"], "force_on_bit")
    assert rms_error(runs["corrected"], "bit_speed") < 0.8 * rms_error(runs["plain"], "bit_speed")
    assert end_error(runs["corrected"], "surface_torque") < 0.05 * end_error(runs["plain"], "surface_torque")
    assert rms_error(runs["corrected"], "surface_torque") < 0.2 * rms_error(runs["plain"], "surface_torque")
