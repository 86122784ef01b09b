"""The published Detournay case in the configuration of its paper's model (``aarsnes2019_paper``: 2000 m of
pipe without BHA, distributed viscous damping k = 1 1/s, the rotary speed imposed at the top and the hook
load axially) against the paper's own characteristic equation, written here independently of the package.

U. J. F. Aarsnes, N. van de Wouw, "Axial and torsional self-excited vibrations of a distributed drill-string",
J. Sound Vib. 444 (2019) 127–151. Its model: two damped wave equations, ``ρA(u_tt + k u_t) = EA u_xx`` and
``ρJ(φ_tt + k φ_t) = GJ φ_xx``, coupled only at the bit through the Detournay law, the depth of cut per blade
``d = u(t) − u(t − t_N)`` with ``φ(t) − φ(t − t_N) = 2π/N``. Linearised about steady drilling (``V``, ``Ω``),
``δd = (1 − e^{−s t_N})(δU − (V/Ω) δΦ)``, the bit's force ``δW = aζεN δd`` and torque ``δT = ½ a²εN δd``, and
the bit's speeds answer them through the strings' admittances at the bit,
``sδU = −g_a(s) δW / (A√(Eρ))`` (top free: ``g_a = s coth(Γ_a L)/(c_a Γ_a)``) and
``sδΦ = −g_t(s) δT / (J√(Gρ))`` (top held: ``g_t = s tanh(Γ_t L)/(c_t Γ_t)``), ``Γ = √(s(s + k))/c``. So

    1 + (1 − e^{−s t_N})/s · (K_a g_a(s) − K_t g_t(s)) = 0,
    K_a = aζεN/(A√(Eρ)),   K_t = (V/Ω) a²εN/(2J√(Gρ)),                                              (★)

the axial loop ``1 + K_a g_a (1 − e^{−s t_N})/s = 0`` and its torsional counterpart (with the opposite sign:
the regenerative torque destabilises) acting together.
"""

import math

import numpy as np
import pytest

from drillstring.case import load_case
from drillstring.dynamics.delay_stability import _newton, _residuals
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.stability import delay_matrices, steady_drilling

# The paper's data (its Table 1), in SI
E, RHO, G = 200e9, 8000.0, 77e9
A_BIT, ZETA, EPS, N_BLADES = 0.108, 0.6, 60e6, 4
LENGTH, K_DAMPING = 2000.0, 1.0
AREA = math.pi / 4 * (0.127**2 - 0.108**2)
POLAR = math.pi / 32 * (0.127**4 - 0.108**4)
C_A, C_T = math.sqrt(E / RHO), math.sqrt(G / RHO)


def characteristic(s, rate_of_penetration, bit_speed):
    """The left-hand side of (★)."""
    delay = 2 * math.pi / (N_BLADES * bit_speed)
    k_a = A_BIT * ZETA * EPS * N_BLADES / (AREA * math.sqrt(E * RHO))
    k_t = (rate_of_penetration / bit_speed) * A_BIT**2 * EPS * N_BLADES / (2 * POLAR * math.sqrt(G * RHO))
    root = np.sqrt(s * (s + K_DAMPING))  # c Γ; g_a and g_t are even in it: either branch
    with np.errstate(all="ignore"):  # a Newton iterate may wander to s = 0: NaN, discarded
        g_a = s / root / np.tanh(root * LENGTH / C_A)
        g_t = s / root * np.tanh(root * LENGTH / C_T)
        return 1 + (1 - np.exp(-s * delay)) / s * (k_a * g_a - k_t * g_t)


def paper_roots(rate_of_penetration, bit_speed, f_max=25.0):
    """The roots of (★) with 0.1 Hz < Im s/2π < ``f_max``, by Newton's method (complex-step-free central
    differences) from a grid of starting values."""
    def newton(s):
        for _ in range(60):
            h = 1e-7 * max(1.0, abs(s))
            slope = (characteristic(s + h, rate_of_penetration, bit_speed)
                     - characteristic(s - h, rate_of_penetration, bit_speed)) / (2 * h)
            with np.errstate(all="ignore"):
                step = characteristic(s, rate_of_penetration, bit_speed) / slope
            s -= step
            if abs(step) < 1e-13 * abs(s):
                break
        return s

    found = []
    for f0 in np.arange(0.25, f_max + 5.0, 0.25):
        for g0 in (-1.0, 0.5):
            s = newton(complex(g0, 2 * math.pi * f0))
            if (np.isfinite(s) and abs(characteristic(s, rate_of_penetration, bit_speed)) < 1e-9
                    and 0.2 * math.pi < s.imag < 2 * math.pi * f_max and not any(abs(s - r) < 1e-6 for r in found)):
                found.append(s)
    return sorted(found, key=lambda s: -s.real)


@pytest.fixture(scope="module")
def paper_case():
    return load_case("aarsnes2019_paper")


@pytest.fixture(scope="module")
def paper_case_10m(paper_case):
    """The case on 10 m elements: the mesh of the basis-convergence tables of docs/verification.md."""
    return paper_case.model_copy(update={"mesh": paper_case.mesh.model_copy(update={"max_element_length": 10.0})})


def _model_root(case, modes: int, start: complex, truncation_correction: str = "none") -> complex:
    """The model's characteristic root (delay system (3) of :mod:`drillstring.dynamics.stability`) nearest
    ``start``, by Newton's method on det Δ, with ``modes`` axial and torsional modes (and the basis's
    truncation correction ``truncation_correction``)."""
    model = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"axial_modes": modes, "torsional_modes": modes, "truncation_correction": truncation_correction})}))
    steady = steady_drilling(model)
    a0, a1 = delay_matrices(model, steady)
    root = complex(_newton(a0, a1, steady.delay, [start])[0])
    assert _residuals(a0, a1, steady.delay, np.array([root]))[0] < 1e-10
    return root


def test_case_is_the_papers_configuration(paper_case):
    """No BHA (one pipe section), damping k M only, the rotary speed imposed, no lateral modes; steady drilling
    at 30 rpm within 1 % of the paper's 30 m/h (the viscous drag α m V on the whole string, 0.5 kN, takes
    0.2 m/h)."""
    assert len(paper_case.sections) == 1 and paper_case.sections[0].length == LENGTH
    damping = paper_case.damping
    assert (damping.mass_proportional, damping.stiffness_proportional, damping.modal_damping_ratio,
            damping.rigid_axial, damping.rigid_rotation) == (K_DAMPING, 0.0, 0.0, 0.0, 0.0)
    assert paper_case.top_drive.controller == "imposed_speed" and paper_case.reduced_model.lateral_modes == 0
    steady = steady_drilling(case_reduced_model(paper_case.model_copy(update={
        "reduced_model": paper_case.reduced_model.model_copy(update={"axial_modes": 4, "torsional_modes": 4})})))
    assert steady.bit_speed == pytest.approx(math.pi, rel=1e-12)
    assert steady.rate_of_penetration * 3600 == pytest.approx(30.0, rel=0.01)


def test_leading_roots_against_the_papers_characteristic_equation(paper_case_10m):
    """The three roots of (★) of largest growth below 25 Hz (7.84, 11.65 and 17.72 Hz, all growing: steady
    drilling is unstable) are roots of the model: their frequencies agree within 0.5 % with 40 modes per
    family and 0.2 % with 80; the growth rates converge like 1/n (the modes left out of the basis carry the
    bit's residual compliance): the error falls from 40 to 80 modes, and the converged-basis limit
    (Richardson, 2 g₈₀ − g₄₀) of the two leading ones agrees within 2 %."""
    case = paper_case_10m
    model = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"axial_modes": 4, "torsional_modes": 4})}))
    steady = steady_drilling(model)
    exact = paper_roots(steady.rate_of_penetration, steady.bit_speed)
    leading = exact[:3]
    assert [round(s.imag / (2 * math.pi), 2) for s in leading] == [7.84, 11.65, 17.72]
    assert all(s.real > 0.5 for s in leading)
    for rank, target in enumerate(leading):
        coarse, fine = (_model_root(paper_case_10m, n, target) for n in (40, 80))
        for root, tolerance in ((coarse, 5e-3), (fine, 2e-3)):
            assert root.imag == pytest.approx(target.imag, rel=tolerance)
        assert abs(fine.real - target.real) < abs(coarse.real - target.real)
        if rank < 2:
            assert 2 * fine.real - coarse.real == pytest.approx(target.real, rel=0.02)


def test_leading_roots_with_the_truncation_correction(paper_case_10m):
    """With the truncation correction (the bit's residual-flexibility attachment modes) a basis of 40 modes per
    family is converged where the plain basis is not: the two leading roots of (★) within 2 % in growth rate
    (measured −0.4 % and +0.7 %; the plain basis at 80 modes: +2.4 % and +10 %) and 0.3 % in frequency."""
    case = paper_case_10m
    model = case_reduced_model(case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"axial_modes": 4, "torsional_modes": 4})}))
    steady = steady_drilling(model)
    for target in paper_roots(steady.rate_of_penetration, steady.bit_speed)[:2]:
        root = _model_root(paper_case_10m, 40, target, truncation_correction="static")
        assert root.imag == pytest.approx(target.imag, rel=3e-3)
        assert root.real == pytest.approx(target.real, rel=0.02)


def test_the_case_as_shipped_gives_the_papers_leading_roots():
    """``drillstring stability aarsnes2019_paper`` as the case ships (40 + 40 modes with the truncation correction,
    2.5 m elements, each root checked on twice the basis): its four resolved roots of largest growth are the four
    leading roots of (★), the two leading ones within 0.1 % in growth rate, the next two within 0.5 %, all four
    within 0.02 % in frequency (measured: −0.02 %, +0.04 %, −0.21 %, +0.46 %; 0.001–0.010 %), and its leading root
    is the paper's. Before, the plain 40 + 40 basis on 10 m elements reported a root of its cut-off (51.3 Hz,
    +1.43 1/s) as the leading one and the three roots 5.6 %, 21 % and 15 % off."""
    from drillstring.dynamics.stability import case_stability

    case = load_case("aarsnes2019_paper")
    assert case.reduced_model.truncation_correction == "static" and case.mesh.max_element_length == 2.5
    found = case_stability(case)
    steady = found.steady_state
    exact = paper_roots(steady.rate_of_penetration, steady.bit_speed)[:4]
    ours = sorted(found.resolved, key=lambda m: -m.growth_rate)[:4]
    for rank, (mode, target) in enumerate(zip(ours, exact)):
        assert mode.converged is True
        assert mode.growth_rate == pytest.approx(target.real, rel=1e-3 if rank < 2 else 5e-3)
        assert mode.frequency == pytest.approx(target.imag / (2 * math.pi), rel=2e-4)
    assert found.leading == ours[0] and not found.stable
