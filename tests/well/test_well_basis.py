"""The dynamics on the well basis (reduced_model.lateral_basis = "well"): the modes about the stiff string's static
state along the path, the spin about each node's tangent, the contact measured from the string's rest
(docs/stiff_string.md, The well basis)."""

import math

import numpy as np
import pytest

from drillstring.case.well_table import Well
from drillstring.dynamics.reduced.build import case_well_basis
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import stability
from drillstring.fem.dofs import THETA_X, dof
from drillstring.modal import case_linear_system, family_modes
from drillstring.well.stiff_string import case_stiff_string
from drillstring.well.well_modes import quota_modes
from tests.well.well_cases import deviated_for_well_basis

AXIAL, TORSIONAL, LATERAL = 3, 3, 4


def _inclined(reference_case, inclination_deg: float, azimuth: float = 0.0, basis: str = "well", *,
              top_speed: float = 0.0, weight_on_bit: float | None = None, law: str = "off_bottom"):
    """The reference string (50 m mesh, a small basis) in a straight hole inclined from the surface."""
    case = reference_case
    angle = math.radians(inclination_deg)
    operation = {"top_speed": top_speed}
    if weight_on_bit is not None:
        operation["weight_on_bit"] = weight_on_bit
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={
            "axial_modes": AXIAL, "torsional_modes": TORSIONAL, "lateral_modes": LATERAL, "lateral_cutoff": 0.0,
            "lateral_basis": basis, "truncation_correction": "none"}),
        "damping": case.damping.model_copy(update={"basis": "constrained"}),
        "operation": case.operation.model_copy(update=operation),
        "bit_rock": case.bit_rock.model_copy(update={"law": law}),
        "well": Well(measured_depth=[0.0, 5000.0], inclination=[angle, angle], azimuth=[azimuth, azimuth]),
    })


@pytest.fixture(scope="module")
def inclined(reference_case):
    return case_reduced_model(_inclined(reference_case, 30.0))


def test_inclined_hole_at_rest_stays_at_rest(inclined):
    """30 deg hole, off bottom, no spin: the static state is the state η = 0 of the well basis; the nodes that
    do not rest on the wall keep their static offsets inside the gap (a contact measured from the hole's axis
    with the motion from rest), the resting ones are in the basis's springs."""
    model = inclined
    assert model.coupled and model.centreline_spin
    # the string lies on the low side: its wall is the basis's springs, its stations' offsets the rest's
    assert len(model.stations) < model.static.mesh.n_nodes // 4
    y = np.zeros(model.state_size)
    assert np.abs(model.rhs(0.0, y)).max() < 1e-9
    assert np.abs(model.rhs_reference(0.0, y)).max() < 1e-9
    assert not model.contact_mask(y).any()


def test_jacobian_at_rest_is_minus_the_squared_frequencies(inclined):
    model = inclined
    n = model.size
    y = np.zeros(model.state_size)
    step = 1e-7
    jac = np.empty((n, n))
    for j in range(n):
        dy = np.zeros_like(y)
        dy[j] = step
        jac[:, j] = (model.rhs(0.0, y + dy)[n:2 * n] - model.rhs(0.0, y - dy)[n:2 * n]) / (2 * step)
    scale = np.abs(model.omega2).max()
    assert np.abs(jac + np.diag(model.omega2)).max() < 1e-6 * scale


def test_compiled_right_hand_side_matches_numpy_in_contact(reference_case):
    """1 deg hole, spinning: the pipe sags across the hole between the resting spans (static offsets 45 to 85 mm,
    its gap 86.5 mm); a lateral state pressing it into the wall: compiled = NumPy to 1e-12."""
    model = case_reduced_model(_inclined(reference_case, 1.0, top_speed=6.0))
    assert np.hypot(*model.station_rest).max() > 0.08
    rng = np.random.default_rng(3)
    y = np.zeros(model.state_size)
    y[:2 * model.size] = rng.standard_normal(2 * model.size) * 30.0
    assert model.contact_mask(y).any()
    compiled, reference = model.rhs(0.7, y), model.rhs_reference(0.7, y)
    assert np.abs(compiled - reference).max() <= 1e-12 * np.abs(reference).max()


def test_hole_turned_about_the_vertical_changes_nothing(reference_case):
    """The same hole at azimuth 1 rad: the frequencies agree to 1e-9, the observables of one state (spinning)
    to 1e-5, the probes' distance from the hole's axis among them."""
    first, turned = (case_reduced_model(_inclined(reference_case, 30.0, azimuth, top_speed=6.0))
                     for azimuth in (0.0, 1.0))
    assert np.allclose(first.angular_frequencies, turned.angular_frequencies, rtol=1e-9, atol=1e-9)
    rng = np.random.default_rng(5)
    y = np.zeros(first.state_size)
    y[:2 * first.size] = rng.standard_normal(2 * first.size) * 0.05
    # the same physical state: the bases agree up to each mode's sign (and within degenerate pairs, not here)
    sign = np.sign(np.sum(first.basis * turned.basis, axis=0))
    y_turned = y.copy()
    y_turned[:2 * first.size] *= np.tile(sign, 2)
    # the probes' v and w are in each node's frame, whose axes across the tangent the hole's turn may turn: left out
    probes = len(first.probe_nodes)
    a, b = (m.observe(0.3, state)[:-2 * probes] for m, state in ((first, y), (turned, y_turned)))
    assert np.allclose(a, b, rtol=1e-5, atol=1e-5 * np.abs(a).max())
    assert np.abs(a[-probes:]).max() > 0.03  # the probe's offset from the hole's axis: its rest on the low side


def test_compressed_inclined_string_buckles_straight_but_rests_on_the_wall(reference_case):
    """60 deg hole, 200 kN on the bit: the straight string's basis is laterally buckled (a root > 0), the well
    basis (the string lying on the low side, held by the wall) is stable laterally."""
    case = _inclined(reference_case, 60.0, top_speed=0.0, weight_on_bit=2e5, law="off_bottom")
    straight = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"lateral_basis": "straight"})}), weight_on_bit=2e5)
    well = case_reduced_model(case, weight_on_bit=2e5)
    assert straight.lowest_lateral_eigenvalue < 0.0
    elastic = well.omega2[1:]
    assert np.all(elastic > 0.0)


def test_refusals_name_what_is_not_supported(reference_case):
    case = _inclined(reference_case, 30.0)
    case = case.model_copy(update={"damping": case.damping.model_copy(update={"basis": "free_free"})})
    with pytest.raises(ValueError, match="lateral_basis = 'well' does not support yet: damping.basis"):
        case_reduced_model(case)
    ramp = _inclined(reference_case, 30.0)
    ramp = ramp.model_copy(update={"initial": ramp.initial.model_copy(update={"start": "ramp"})})
    with pytest.raises(ValueError, match="initial.start = 'ramp'"):
        case_reduced_model(ramp)


@pytest.fixture(scope="module")
def deviated():
    """The ``deviated`` case on a 30 m mesh, the constrained damping and the start on bottom (the well basis's)."""
    return deviated_for_well_basis(30.0)


def test_spin_about_the_centreline_stores_nothing_and_torsion_is_the_straight_strings(deviated):
    """The curved string turned about its centreline (θx = 1 at every node, nodes' frames): no energy in K + K_g
    (1e-10 of the twist's scale), and the first torsional mode of the well basis that of the straight string
    (read plainly, the chords' bending made it 26 % too stiff on the 10 m mesh)."""
    state = case_stiff_string(deviated)
    system, basis = case_well_basis(deviated, state)
    spin = np.zeros(state.mesh.n_dofs)
    spin[dof(np.arange(state.mesh.n_nodes), THETA_X)] = 1.0
    scale = system.stiffness.diagonal()[dof(np.arange(state.mesh.n_nodes), THETA_X)].sum()
    assert abs(spin @ (system.stiffness @ spin)) < 1e-10 * scale
    modes, kinds = quota_modes(system, basis.slide, 3, 3, 4)
    torsional = modes.angular_frequencies[kinds == 1][0]
    straight = family_modes(case_linear_system(deviated, state.static_state()), "torsional", 1)
    assert torsional == pytest.approx(straight.angular_frequencies[0], rel=1e-4)  # measured 2.3e-6


def test_deviated_drilling_is_stable_on_the_well_basis(deviated):
    """Drilling in ``deviated``: the straight string's lateral modes under the well's axial force are buckled
    (+0.20 1/s); about the string resting on the wall every root decays, and the torsional roots agree; at rest
    no contact station is pressed."""
    found = {}
    for basis in ("straight", "well"):
        case = deviated.model_copy(update={"reduced_model": deviated.reduced_model.model_copy(
            update={"lateral_basis": basis})})
        model = case_reduced_model(case)
        found[basis] = stability(model)
    # at rest no station touches, its gap the statics' (on the 10 m mesh the open hole's gap in the casing, 44.4 mm,
    # put a span sagging 45.6 mm off the axis 1.2 mm into the wall: 11 MN at t = 0; the casing's is 46.7 mm)
    assert not model.contact_mask(np.zeros(model.state_size)).any()
    well = deviated.well
    cased = model.static.mesh.nodes[model.stations.node] < well.casing_shoe
    assert cased.any()
    assert np.allclose(model.stations.gap[cased],
                       0.5 * (well.casing_inner_diameter - model.stations.outer_diameter[cased]))
    assert found["straight"].leading.family == "lateral"
    assert found["straight"].leading.growth_rate == pytest.approx(0.20, abs=0.01)  # measured 0.2014
    assert found["well"].leading.growth_rate < -0.1  # measured -0.190
    straight, well = (next(m for m in found[b].modes if m.family == "torsional") for b in ("straight", "well"))
    assert well.frequency == pytest.approx(straight.frequency, rel=1e-3)
    assert well.growth_rate == pytest.approx(straight.growth_rate, rel=1e-3)


def test_vertical_hole_gives_the_straight_basis(reference_case):
    """No [well] (the vertical hole as deep as the string): every frame the identity, the slide the rigid
    translation, the kinds the families: the well basis has the straight basis's frequencies (1e-9)."""
    case = _inclined(reference_case, 0.0).model_copy(update={"well": None})
    straight = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"lateral_basis": "straight"})}))
    well = case_reduced_model(case)
    assert np.allclose(np.sort(well.angular_frequencies), np.sort(straight.angular_frequencies), rtol=1e-9,
                       atol=1e-9)
    assert sorted(well.family) == sorted(f if not f.startswith("lateral") else "lateral" for f in straight.family)
