"""One drilling run: tolerance and mode-count convergence, failure handling, impact counting."""

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model

T_END = 6.0


def run(case, rtol=1e-6, **modes):
    rom = case_reduced_model(case, **modes)
    return simulate_model(rom, t_end=T_END, output_step=0.01, rtol=rtol, atol=rtol * 1e-3,
                          lateral_perturbation=case.initial.lateral_perturbation)


def history_error(a, b, name):
    x, y = a.observables[name], b.observables[name]
    return np.sqrt(np.mean((x - y) ** 2)) / np.sqrt(np.mean(y**2))


def test_results_converge_as_rtol_is_tightened(coarse_case):
    ref = run(coarse_case, rtol=1e-9)
    errors = {rtol: history_error(run(coarse_case, rtol=rtol), ref, "bit_speed")
              for rtol in (1e-3, 1e-5, 1e-7)}
    assert errors[1e-7] < errors[1e-5] < errors[1e-3]
    assert errors[1e-7] < 1e-6


def test_results_converge_as_axial_and_torsional_modes_grow(coarse_case):
    ref = run(coarse_case, axial_modes=12, torsional_modes=12, lateral_modes=2)
    err = [history_error(run(coarse_case, axial_modes=n, torsional_modes=n, lateral_modes=2), ref,
                         "rate_of_penetration") for n in (1, 3, 6)]
    assert err[2] < err[1] < err[0]
    assert err[2] < 0.01


def test_failure_keeps_computed_outputs_and_says_when(coarse_case):
    case = coarse_case.model_copy(update={
        "simulation": coarse_case.simulation.model_copy(update={"max_steps": 60})})
    rom = case_reduced_model(case, lateral_modes=2)
    with pytest.raises(SimulationError, match=r"t = [0-9.]+ s") as info:
        simulate_model(rom, t_end=T_END, output_step=0.01, max_steps=60)
    partial = info.value.result
    assert partial.status == "failed"
    assert 0 < len(partial.time) < T_END / 0.01
    assert np.all(np.isfinite(partial.observables["rate_of_penetration"]))
    returned = simulate_model(rom, t_end=T_END, output_step=0.01, max_steps=60,
                              raise_on_failure=False)
    assert returned.status == "failed" and "t =" in returned.message


def test_impacts_are_counted_when_the_string_touches(coarse_case):
    """A centred string never touches; one released beyond the wall is pushed back and rattles."""
    case = coarse_case.model_copy(update={
        "damping": coarse_case.damping.model_copy(update={"modal_damping_ratio": 0.01})})
    rom = case_reduced_model(case, lateral_modes=6)
    gap = rom.gap.min()
    centred = simulate_model(rom, t_end=3.0, output_step=0.005, lateral_perturbation=0.0)
    assert centred.impacts == 0 and centred.observables["nodes_in_contact"].max() == 0
    released = simulate_model(rom, t_end=3.0, output_step=0.005, lateral_perturbation=2.0 * gap)
    assert released.impacts > 0
    assert released.observables["nodes_in_contact"].max() >= 1
    # The wall pushes back: the probe never goes far past the wall (k_sh = 1e8 N/m).
    assert released.radial_displacement.max() < 2.0 * gap


def sticking_case(case, stiffening_limit):
    """The coarse reference string with a sharper bit–rock law (e = 0.5 rad/s) at 140 kN: the bit sticks."""
    return case.model_copy(update={
        "reduced_model": case.reduced_model.model_copy(update={"lateral_modes": 0, "lateral_cutoff": 0.0}),
        "bit_rock": case.bit_rock.model_copy(update={"regularization": 0.5,
                                                     "stick_stiffening_limit": stiffening_limit}),
        "operation": case.operation.model_copy(update={"weight_on_bit": 140e3}),
    })


def test_stick_slip_integrates_and_converges_with_the_stiffening_limit(coarse_case):
    """With the default limit a sticking run integrates (without it the step size collapses within
    1 s); its indicators change by < 1e-3 when the limit is raised 30-fold."""
    from drillstring.dynamics.indicators import drilling_indicators

    results = {}
    for limit in (100.0, 3000.0):
        model = case_reduced_model(sticking_case(coarse_case, limit))
        run = simulate_model(model, t_end=20.0, output_step=0.01, lateral_perturbation=0.0)
        results[limit] = drilling_indicators(run.time, run.observables["rate_of_penetration"],
                                             run.observables["bit_speed"], model.top_speed, 10.0)
    default, tight = results[100.0], results[3000.0]
    assert default["bit_speed_min"] < 0.01 * coarse_case.operation.top_speed  # it sticks
    assert default["stick_time_fraction"] > 0.2 and default["stick_slip"]
    assert default["bit_speed_oscillation"] > 1.0
    for key in ("mean_rate_of_penetration", "bit_speed_oscillation"):
        assert default[key] == pytest.approx(tight[key], rel=1e-3)
    assert default["stick_time_fraction"] == pytest.approx(tight["stick_time_fraction"], abs=2e-3)


def test_a_buckled_string_comes_to_rest_on_the_wall_with_the_static_lateral_load(reference_case):
    """At 170 kN (critical 114 kN) the straight string is unstable: released along its unstable mode at
    90 % of the collar's gap, it hits the wall, bounces and settles on it. At rest the wall's force on the
    string equals the static lateral load of the finite-element model pushed against the wall (all
    lateral DOFs, the same wall stations, solved statically: tests/exact_solutions.py), within the
    lateral basis' truncation (40 modes per plane: measured 0.01 %)."""
    from drillstring.fem.dofs import V, dof
    from drillstring.modal import family_dofs

    from exact_solutions import beam_resting_on_a_wall

    model = case_reduced_model(reference_case, weight_on_bit=170e3, lateral_modes=40)
    n = model.size
    first = model.family.index("lateral_y")
    assert model.omega2[first] < 0  # buckled
    shape = model.phi_v[:, first]
    peak = int(np.argmax(np.abs(shape)))
    y0 = np.zeros(2 * n)
    y0[first] = 0.9 * model.gap[peak] / shape[peak]  # towards +y
    run = simulate_model(model, t_end=60.0, output_step=0.01, initial_state=y0)
    force = run.observables["contact_force"]
    last = force[run.time >= 55.0]
    assert run.impacts >= 1 and last.min() > 0.0
    assert np.ptp(last) < 1e-3 * last.mean()  # at rest

    system, stations = model.system, model.stations
    dofs = family_dofs(system.mesh, "lateral_y")
    position = {int(d): i for i, d in enumerate(dofs)}
    inner = np.array([dof(node, V) in position for node in stations.node])  # not the pinned ends
    rows = np.array([position[dof(node, V)] for node in stations.node[inner]])
    stiffness = system.stiffness[dofs][:, dofs]
    start = np.zeros(len(dofs))
    start[rows] = 1.5 * stations.gap[inner] * model.phi_v[stations.node[inner], first] / shape[peak]
    _, wall = beam_resting_on_a_wall(stiffness, rows, model.station_stiffness[inner], stations.gap[inner], start)
    assert wall.sum() == pytest.approx(last.mean(), rel=2e-3)
    assert 50.0 < wall.sum() < 200.0  # ~92 N: near-critical strings lean on the wall lightly
    # at the same place: the nodes touching at the end of the run and in the static solve
    assert set(stations.node[inner][wall > 0]) == set(np.nonzero(model.contact_mask(run.state.y))[0])


def _thrown_collar(case, *, max_element_length, lateral_modes):
    """The reference string with its collar's lowest lateral mode moving at 0.1 m/s (at its peak, towards
    +y) and no other motion: it hits the wall at t = 0.363 s and rattles. Returns the run over 1 s (outputs
    every 0.5 ms) and the first impact: (peak force [N], impulse [N·s])."""
    mesh = case.mesh.model_copy(update={"max_element_length": max_element_length})
    model = case_reduced_model(case.model_copy(update={"mesh": mesh}), lateral_modes=lateral_modes,
                               lateral_cutoff=0.0)
    n = model.size
    first = model.family.index("lateral_y")
    shape = model.phi_v[:, first]
    y0 = np.zeros(2 * n)
    y0[n + first] = 0.1 / shape[np.argmax(np.abs(shape))]
    run = simulate_model(model, t_end=1.0, output_step=5e-4, rtol=1e-9, atol=1e-12, initial_state=y0)
    force = run.observables["contact_force"]
    start = int(np.argmax(force > 0))
    end = start + int(np.argmax(force[start:] == 0))
    return run, force[start:end].max(), force[start:end].sum() * 5e-4


def test_impacts_and_radial_response_converge_as_the_mesh_is_refined(reference_case):
    """With the wall a distributed stiffness (per metre of string), refining the mesh at a fixed lateral
    basis (20 modes per plane) converges: the same number of impacts on the two finest meshes, and the
    first impact's peak force and impulse and the RMS radial displacement at the probe approach the
    finest mesh's, within 2 % on the 5 m mesh. (A per-node wall stiffness would have doubled the wall's
    stiffness at each halving.)"""
    runs = {h: _thrown_collar(reference_case, max_element_length=h, lateral_modes=20) for h in (10.0, 5.0, 2.5)}
    impacts = {h: run.impacts for h, (run, _, _) in runs.items()}
    assert impacts[5.0] == impacts[2.5] >= 3
    rms = {h: np.sqrt(np.mean(run.radial_displacement[:, 0] ** 2)) for h, (run, _, _) in runs.items()}
    for values in (rms, {h: peak for h, (_, peak, _) in runs.items()},
                   {h: impulse for h, (_, _, impulse) in runs.items()}):
        error = {h: abs(values[h] / values[2.5] - 1) for h in (10.0, 5.0)}
        assert error[5.0] < error[10.0] and error[5.0] < 0.02, values


def test_impacts_and_radial_response_converge_with_the_lateral_modes(reference_case):
    """On a 20 m mesh (158 lateral modes per plane in all), adding lateral modes converges to the full
    model: the first impact's peak force and impulse fall monotonically towards it (a truncated basis is
    too stiff where the string hits the wall), within 1.5 % and 3 % from 120 modes; the number of impacts is the
    full model's from 40 modes, and the RMS radial displacement is within 3 % from 120 modes."""
    counts = (20, 40, 80, 120, 158)
    runs = {m: _thrown_collar(reference_case, max_element_length=20.0, lateral_modes=m) for m in counts}
    full, peak_full, impulse_full = runs[158]
    assert full.impacts >= 3
    for m in counts[1:]:
        assert runs[m][0].impacts == full.impacts
    for index, bound in ((1, 0.015), (2, 0.03)):  # peak (measured 1.0 % at 120 modes), impulse (2.3 %)
        error = [abs(runs[m][index] / runs[158][index] - 1) for m in counts[:-1]]
        assert all(a > b for a, b in zip(error, error[1:])) and error[-1] < bound, error
    rms = {m: np.sqrt(np.mean(run.radial_displacement[:, 0] ** 2)) for m, (run, _, _) in runs.items()}
    assert abs(rms[120] / rms[158] - 1) < 0.03
