"""Stiff-string statics along the well path against closed forms, an independent beam-column solution, the
vertical statics and the soft string (drillstring.well.stiff_string)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from drillstring.case import load_case
from drillstring.fem.assembly import Stabilizer
from drillstring.fem.mesh import build_mesh
from drillstring.fem.sections import hollow_circle
from drillstring.statics import case_static_state
from drillstring.well import stiff_string as ss
from drillstring.well.stiff_string import (
    case_static_state_in_well,
    case_stiff_string,
    solve_stiff_string,
    wall_stations,
)
from drillstring.well.survey import trajectory
from drillstring.well.torque_drag import case_torque_drag

DEG = math.pi / 180.0
PIPE = hollow_circle(0.127, 0.1086, 207e9, 7850.0, 0.3)  # 5 in drill pipe
HOLE = 0.2159  # 8 1/2 in
GAP = (HOLE - 0.127) / 2.0
WALL = 1e8  # N/m per m


def _solve(length, step, inclination, weight, bit_force=0.0, end_inclination=None, azimuth=0.0, **kwargs):
    mesh = build_mesh([length], [PIPE], step)
    end = inclination if end_inclination is None else end_inclination
    path = trajectory([0.0, length], [inclination, end], [azimuth, azimuth])
    stations = wall_stations(mesh, [0.127], HOLE, WALL)
    return path, solve_stiff_string(mesh, path, [weight], stations, bit_force=bit_force, **kwargs)


@pytest.mark.parametrize("inclination", [30.0, 60.0])
def test_straight_inclined_hole_is_the_soft_string_away_from_the_ends(inclination):
    """Far from the ends the string lies on the low side: side force w sin I per length, axial force
    w cos I (L − s) (exact: the wall's force is across the axis), no bending but the span's q h²/12 between
    the nodal supports."""
    w, length, step = 300.0, 400.0, 5.0
    _, state = _solve(length, step, inclination * DEG, w)
    x = state.measured_depth
    middle = (x > 100.0) & (x < 300.0)
    inc = inclination * DEG
    assert np.allclose(state.side_force_per_length[middle], w * math.sin(inc), rtol=1e-9)
    assert np.allclose(state.axial_force, w * math.cos(inc) * (length - x), rtol=0, atol=1e-6)
    assert np.allclose(np.diff(state.axial_force) / np.diff(x), -w * math.cos(inc), rtol=1e-9)
    # the wall pushes up, across the axis: along -(x̂ - (x̂·t) t)
    t = state.tangent[0]
    low_side = np.array([1.0, 0.0, 0.0]) - t[0] * t
    direction = state.wall_force[middle] / state.side_force[middle][:, None]
    assert np.allclose(direction, -low_side / np.linalg.norm(low_side), atol=1e-9)
    assert np.allclose(state.lateral_offset[middle], GAP + w * math.sin(inc) * step / (WALL * step), rtol=1e-9)
    assert np.allclose(state.bending_moment[middle], w * math.sin(inc) * step**2 / 12.0, rtol=1e-6)
    assert state.hook_load == pytest.approx(w * math.cos(inc) * length, rel=1e-12)


def _beam_column_end(ei, q, gap, tension):
    """Independent solution of the string's end span in a straight horizontal hole: held on the axis at
    x = 0 (a height ``gap`` above the wall), lying on the wall beyond the touchdown x = l. EI y'''' − T y''
    = −q on (0, l) with y(0) = gap, y''(0) = 0, y(l) = y'(l) = y''(l) = 0 (moment continuous onto the
    straight part on the wall). Returns l and the support's lateral reaction EI y'''(0) − T y'(0)."""
    lam = math.sqrt(tension / ei)

    def parts(x):
        """Rows: y, y', y'', y''' of the homogeneous basis (4 columns) and the particular solution."""
        if tension == 0.0:
            basis = np.array([[1, x, x * x, x**3], [0, 1, 2 * x, 3 * x * x], [0, 0, 2, 6 * x], [0, 0, 0, 6]])
            particular = np.array([-q * x**4 / (24 * ei), -q * x**3 / (6 * ei), -q * x * x / (2 * ei), -q * x / ei])
        else:
            c, s = math.cosh(lam * x), math.sinh(lam * x)
            basis = np.array([[1, x, c, s], [0, 1, lam * s, lam * c], [0, 0, lam**2 * c, lam**2 * s],
                              [0, 0, lam**3 * s, lam**3 * c]])
            particular = np.array([q * x * x / (2 * tension), q * x / tension, q / tension, 0.0])
        return basis, particular

    def solve(length):
        (b0, p0), (bl, pl) = parts(0.0), parts(length)
        matrix = np.array([b0[0], b0[2], bl[0], bl[1]])
        coefficients = np.linalg.solve(matrix, [gap - p0[0], -p0[2], -pl[0], -pl[1]])
        return coefficients, bl[2] @ coefficients + pl[2]

    grid = np.arange(0.5, 100.0, 0.05)
    moment = [solve(x)[1] for x in grid]
    k = next(i for i in range(len(grid) - 1) if moment[i] * moment[i + 1] <= 0.0)
    touchdown = brentq(lambda x: solve(x)[1], grid[k], grid[k + 1])
    coefficients, _ = solve(touchdown)
    b0, p0 = parts(0.0)
    return touchdown, ei * (b0[3] @ coefficients + p0[3]) - tension * (b0[1] @ coefficients + p0[1])


@pytest.mark.parametrize("tension", [0.0, 1e5])
def test_bit_span_against_an_independent_beam_column(tension):
    """Horizontal hole (no axial weight: N = the bit's pull everywhere): the bit held on the axis, the
    string lying on the wall behind it. The bit's lateral reaction against the beam-column solution (for
    T = 0: q l / 2 with l = (24 EI g / q)^(1/4)); the tension (K_g) raises it by 58 %."""
    w = 250.0
    _, state = _solve(100.0, 0.25, 90.0 * DEG, w, bit_force=tension)
    touchdown, reaction = _beam_column_end(PIPE.bending_stiffness, w, GAP, tension)
    if tension == 0.0:
        assert touchdown == pytest.approx((24.0 * PIPE.bending_stiffness * GAP / w) ** 0.25, rel=1e-9)
        assert reaction == pytest.approx(w * touchdown / 2.0, rel=1e-9)
    t = state.tangent[-1]
    lateral = state.bit_reaction - (state.bit_reaction @ t) * t
    assert np.linalg.norm(lateral) == pytest.approx(abs(reaction), rel=2e-4)
    x = state.measured_depth
    last_contact = x[-1] - x[np.nonzero(state.in_contact)[0].max()]
    assert abs(last_contact - touchdown) <= 0.5  # two elements: the wall touches only at nodes
    assert np.allclose(state.axial_force, tension, rtol=1e-8)


@pytest.mark.parametrize("weight", [0.0, 300.0])
def test_uniform_arc_against_the_soft_string_and_the_bent_pipe(weight):
    """A build of 40 deg over 600 m (κ = 1.16e-3 1/m) in azimuth 30 deg, pulled at the bit by 200 kN. In the
    middle, in full contact: side force |N κ + w (x̂ − (x̂·t) t)| per length with the frictionless N(s) =
    T + w (sin I_L − sin I(s))/κ; without weight the pipe bent to the hole carries EI κ."""
    length, build, tension = 600.0, 40.0 * DEG, 2e5
    kappa = build / length
    path, state = _solve(length, 5.0, 0.0, weight, bit_force=tension, end_inclination=build, azimuth=30 * DEG)
    x = state.measured_depth
    middle = (x > 150.0) & (x < 450.0)
    assert np.all(state.in_contact[middle])
    axial = tension + weight * (math.sin(build) - np.sin(kappa * x)) / kappa
    _, t, curvature, _ = path.locate(x)
    low_side = np.array([0.0, 0.0, 1.0]) - t[:, 2:] * t  # (north, east, down)
    side = np.linalg.norm(axial[:, None] * curvature + weight * low_side, axis=1)
    # chords: per node N 2 sin(κh/2) = N κ h (1 − (κh)²/24), 5.6e-6 less
    assert np.allclose(state.side_force_per_length[middle], side[middle], rtol=2e-5)
    assert np.allclose(state.axial_force, axial, rtol=2e-5)
    assert state.hook_load == pytest.approx(axial[0], rel=1e-5)
    if weight == 0.0:
        assert np.allclose(state.bending_moment[middle], PIPE.bending_stiffness * kappa, rtol=1e-3)
        # the wall pushes the string away from the centre of curvature
        pushes = np.einsum("ij,ij->i", state.wall_force[middle], curvature[middle][:, [2, 0, 1]])
        assert np.all(pushes < 0.0)


def test_vertical_hole_is_the_vertical_statics(reference_case):
    """No [well]: the string hangs in a vertical hole: no side force, no lateral displacement, the axial
    force and hook load of statics.solve_statics; the selection returns today's static state itself."""
    state = case_stiff_string(reference_case)
    statics = case_static_state(reference_case)
    assert np.allclose(state.axial_force, statics.axial_force, rtol=0, atol=1e-9 * statics.weight)
    assert state.hook_load == pytest.approx(statics.weight_on_hook, rel=1e-12)
    assert state.weight == pytest.approx(statics.weight, rel=1e-12)
    assert np.all(state.side_force == 0.0)
    assert np.all(state.lateral_offset == 0.0)
    assert np.all(state.rotations == np.eye(3))
    selected = case_static_state_in_well(reference_case)
    assert np.array_equal(selected.axial_force, statics.axial_force)
    assert selected.weight_on_hook == statics.weight_on_hook


def test_no_convergence_names_the_iterations_and_the_residual():
    with pytest.raises(ValueError, match=r"did not converge in 1 Newton iterations: residual [0-9.e+]+ N"):
        _solve(400.0, 5.0, 60.0 * DEG, 300.0, max_iterations=1)


def test_bad_input_is_named():
    mesh = build_mesh([100.0], [PIPE], 10.0)
    with pytest.raises(ValueError, match="outer_diameter = 0.3 m"):
        wall_stations(mesh, [0.3], HOLE, WALL)
    with pytest.raises(ValueError, match="wall_stiffness"):
        wall_stations(mesh, [0.127], HOLE, -1.0)
    path = trajectory([0.0, 50.0], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="must fit in the well"):
        solve_stiff_string(mesh, path, [300.0], wall_stations(mesh, [0.127], HOLE, WALL))
    path = trajectory([0.0, 100.0], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="weight"):
        solve_stiff_string(mesh, path, [300.0, 1.0], wall_stations(mesh, [0.127], HOLE, WALL))


def test_wall_tangent_is_the_derivative_of_its_force():
    """The penalty's tangent k [n nᵀ + (1 − g/r)(P − n nᵀ)] against central differences of f_c."""
    rng = np.random.default_rng(3)
    n = 4
    tangent = rng.normal(size=(n, 3))
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    stations = ss.WallStations(node=np.array([0, 1, 2, 3, 1]), clearance=np.array([0.01, 0.02, 0.5, 0.03, 0.0]),
                               stiffness=np.array([1e6, 2e6, 1e6, 3e6, 5e5]), length=np.ones(5))
    q = rng.normal(scale=0.05, size=6 * n)
    force, energy, stiffness = ss._wall(q, stations, tangent, 6 * n)
    assert energy > 0.0
    step = 1e-7
    numeric = np.zeros((6 * n, 6 * n))
    for j in range(6 * n):
        dq = np.zeros(6 * n)
        dq[j] = step
        numeric[:, j] = (ss._wall(q + dq, stations, tangent, 6 * n)[0] - ss._wall(q - dq, stations, tangent, 6 * n)[0]) / (2 * step)
    assert np.allclose(stiffness.toarray(), numeric, rtol=1e-6, atol=1e-6 * np.abs(numeric).max())
    # and the force is the energy's gradient
    grad = np.array([(ss._wall(q + step * e, stations, tangent, 6 * n)[1] - ss._wall(q - step * e, stations, tangent, 6 * n)[1])
                     / (2 * step) for e in np.eye(6 * n)])
    assert np.allclose(force, grad, rtol=1e-6, atol=1e-6 * np.abs(force).max())


def test_stabilizer_is_a_lateral_spring_across_the_path():
    """A stabilizer in an inclined hole carries w sin I of its neighbourhood across the path, nothing along."""
    mesh = build_mesh([200.0], [PIPE], 5.0, [100.0])
    path = trajectory([0.0, 200.0], [45 * DEG, 45 * DEG], [0.0, 0.0])
    stations = wall_stations(mesh, [0.127], HOLE, WALL)
    state = solve_stiff_string(mesh, path, [300.0], stations, stabilizers=[Stabilizer(100.0, 1e8)])
    node = mesh.node_index(100.0)
    assert abs(state.wall_force[node] @ state.tangent[node]) < 1e-9 * state.side_force[node]
    assert state.side_force[node] > 0.0
    # total lateral load carried by wall, stabilizer and the supports = w sin I L
    assert state.total_side_force == pytest.approx(300.0 * math.sin(45 * DEG) * 200.0, rel=1e-9)


@pytest.fixture(scope="module")
def deviated():
    return load_case("deviated")


@pytest.mark.parametrize("operation, weight_on_bit", [("rotating_off_bottom", 0.0), ("drilling", None)])
def test_deviated_case_against_the_soft_string(deviated, operation, weight_on_bit):
    """The deviated case with the wall frictionless: the stiff string's hook load within 2e-5 of the soft
    string's (measured 1.2e-5 and 1.3e-5: the stiff string's shear along the curved path), its total side
    force 1.5 % and 1.6 % above (bending: the stiff collars and the near-bit stabilizer carry the bottom's
    weight in concentrated forces, the pipe leaves the wall at the kick-off and below the casing shoe), within
    2.5 %; node by node the same side force per length as the soft string's in the build, in full contact."""
    state = case_stiff_string(deviated, weight_on_bit=weight_on_bit)
    soft = case_torque_drag(deviated, [operation], cased_friction=0.0, open_hole_friction=0.0,
                            with_buckling=False)[operation]
    assert state.hook_load == pytest.approx(soft.hook_load, rel=2e-5)
    total = np.trapezoid(soft.side_force, soft.measured_depth)
    assert 0.0 < state.total_side_force / total - 1.0 < 0.025
    x = state.measured_depth
    build = (x >= 540.0) & (x <= 870.0)  # the build (500-900 m) less the kick-off's bend: full contact
    assert np.all(state.in_contact[build])
    soft_at_nodes = np.interp(x[build], soft.measured_depth, soft.side_force)
    assert np.allclose(state.side_force_per_length[build], soft_at_nodes, rtol=5e-4)  # measured 1.3e-4
    statics = case_static_state_in_well(deviated)
    assert statics.weight_on_hook == pytest.approx(case_stiff_string(deviated).hook_load, rel=1e-12)


def test_stability_changes_at_the_dawson_paslay_load():
    """A string in compression P lying on the low side of a horizontal hole: the wall's rolling spring F/r
    (w/r per length) and the compression's K_g make it a beam on a foundation, which buckles sideways at
    P = 2 sqrt(EI w / r) (Dawson & Paslay 1984, SPE 11167, at I = 90 deg). The iteration finds the string on
    the low side either way; its tangent stiffness says whether that state is stable, 1 % either side."""
    w = 250.0
    critical = 2.0 * math.sqrt(PIPE.bending_stiffness * w / GAP)
    below = _solve(200.0, 1.0, 90.0 * DEG, w, bit_force=-0.99 * critical)[1]
    above = _solve(200.0, 1.0, 90.0 * DEG, w, bit_force=-1.01 * critical)[1]
    assert np.allclose(below.axial_force, -0.99 * critical, rtol=1e-9)
    assert below.unstable_directions() == 0
    assert above.unstable_directions() > 0


def test_a_hundred_times_stiffer_wall_changes_only_the_penetration(deviated):
    """The wall's penalty is a numerical device: the deviated case at 1e8 and 1e10 N/m per m converges
    (the Newton steps move the nodes in contact round the wall) to the same loads within 1e-5."""
    soft_wall = case_stiff_string(deviated, weight_on_bit=0.0)
    hard_wall = case_stiff_string(deviated, weight_on_bit=0.0, wall_stiffness=1e10)
    assert hard_wall.iterations < 30
    assert hard_wall.hook_load == pytest.approx(soft_wall.hook_load, rel=1e-8)
    assert hard_wall.total_side_force == pytest.approx(soft_wall.total_side_force, rel=1e-5)
    x = soft_wall.measured_depth
    assert np.allclose(hard_wall.side_force_per_length, soft_wall.side_force_per_length, rtol=0,
                       atol=1e-3 * soft_wall.side_force_per_length.max())
    contact = soft_wall.in_contact & hard_wall.in_contact
    assert np.all(hard_wall.lateral_offset[contact] - soft_wall.lateral_offset[contact] < 0.0)
    assert x[-1] == deviated.length
