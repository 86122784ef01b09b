"""Additive (implicit–explicit) Runge–Kutta pairs as validated data: the methods of the IMEX step
(:mod:`drillstring.dynamics.steps.imex_ark`).

An additive Runge–Kutta (ARK) method integrates ``y' = f_E(y) + f_I(y)`` with an explicit tableau
``(a^E, c)`` for ``f_E`` and a diagonally implicit one ``(a^I, c)`` for ``f_I``, sharing the weights::

    Y_i = y_n + h Σ_{j<i} a^E_ij f_E(Y_j) + h Σ_{j≤i} a^I_ij f_I(Y_j),     y_{n+1} = y_n + h Σ_i b_i (f_E + f_I)(Y_i)

C. A. Kennedy & M. H. Carpenter, "Additive Runge–Kutta schemes for convection–diffusion–reaction equations",
Appl. Numer. Math. 44 (2003) 139–181 (K&C below) built pairs whose implicit part is an ESDIRK (``a^I_11 = 0``,
``a^I_ii = γ`` for i ≥ 2) that is L-stable and stiffly accurate (``a^I_s = b``), whose explicit part has the same
nodes ``c``, with an embedded solution ``b̂`` (the same for both parts) and a continuous extension
``b*_i(θ)`` (also shared). Because ``b``, ``b̂`` and ``b*`` are shared, the solution, its error estimate
``h Σ (b_i − b̂_i) f(Y_i)`` and its dense output ``y_n + h Σ b*_i(θ) f(Y_i)`` need only the full right-hand side
at the stages: the same form as an explicit pair's (:mod:`drillstring.dynamics.runge_kutta`).

Order conditions of an ARK method (K&C §3; Hairer–Nørsett–Wanner I §II.15, "P-series"): for every rooted tree
whose vertices are coloured E or I, ``Σ_i b_i Φ_i(τ) = 1/γ(τ)``, the elementary weight ``Φ`` taking ``a^E``
or ``a^I`` along each edge according to the colour of its child vertex; the mixed-colour trees are the
*coupling conditions*. ``tests/dynamics/test_additive_rk.py`` checks them all up to each pair's order (and
that they fail at the next order), the embedded solution's, and those of the continuous extension.

Methods (coefficients from K&C, Tables 3–6 and their appendix; the continuous extensions as published with
them):

- :data:`ARK3_2_4L` — ARK3(2)4L[2]SA: 4 stages (3 implicit, γ ≈ 0.4359), order 3, embedded order 2, dense
  output of order 2.
- :data:`ARK4_3_6L` — ARK4(3)6L[2]SA: 6 stages (5 implicit, γ = 1/4), order 4, embedded order 3, dense
  output of order 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from drillstring.dynamics.tableaus import EmbeddedPair, _readonly

__all__ = ["AdditiveTableau", "ARK3_2_4L", "ARK4_3_6L", "IMEX_TABLEAUS"]

_TOL = 1e-12


@dataclass(frozen=True, eq=False)
class AdditiveTableau(EmbeddedPair):
    """An additive Runge–Kutta pair (module docstring): explicit ``a_explicit`` (s, s), strictly lower
    triangular; implicit ``a_implicit`` (s, s), ESDIRK (first stage explicit, constant diagonal ``gamma``
    after it); nodes ``c`` shared; weights ``b`` and embedded ``b_hat`` shared; ``dense`` (s, p) the shared
    continuous extension ``b*_i(θ) = Σ_p dense[i, p] θ^(p+1)``. Construction checks the shapes, the
    triangular structure, ``Σ_j a_ij = c_i`` for both parts, ``Σ b = Σ b̂ = 1``, ``b*(1) = b`` and, when
    ``stiffly_accurate``, ``a^I_s = b``. Arrays are stored as read-only copies."""

    name: str
    a_explicit: np.ndarray
    a_implicit: np.ndarray
    c: np.ndarray
    b: np.ndarray
    b_hat: np.ndarray
    order: int
    error_order: int
    dense: np.ndarray
    stiffly_accurate: bool = True
    gamma: float = field(init=False)
    error_weights: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        ae, ai = _readonly(self.a_explicit, 2), _readonly(self.a_implicit, 2)
        c, b, b_hat, dense = (_readonly(self.c, 1), _readonly(self.b, 1), _readonly(self.b_hat, 1),
                              _readonly(self.dense, 2))
        s = c.shape[0]
        if ae.shape != (s, s) or ai.shape != (s, s) or b.shape != (s,) or b_hat.shape != (s,) \
                or dense.shape[0] != s:
            raise ValueError(f"{self.name}: inconsistent shapes a_explicit{ae.shape}, a_implicit{ai.shape}, "
                             f"c{c.shape}, b{b.shape}, b_hat{b_hat.shape}, dense{dense.shape}")
        if np.any(np.triu(ae) != 0.0):
            raise ValueError(f"{self.name}: a_explicit must be strictly lower triangular")
        if np.any(np.triu(ai, 1) != 0.0):
            raise ValueError(f"{self.name}: a_implicit must be lower triangular (diagonally implicit)")
        gamma = float(ai[1, 1]) if s > 1 else 0.0
        if ai[0, 0] != 0.0 or not np.allclose(np.diag(ai)[1:], gamma, rtol=0.0, atol=_TOL) or not gamma > 0.0:
            raise ValueError(f"{self.name}: a_implicit must be an ESDIRK (a_11 = 0, a_ii = γ > 0 after it)")
        for label, a in (("a_explicit", ae), ("a_implicit", ai)):
            if not np.allclose(a.sum(axis=1), c, rtol=0.0, atol=_TOL):
                raise ValueError(f"{self.name}: row sums of {label} must equal c")
        if abs(b.sum() - 1.0) > _TOL or abs(b_hat.sum() - 1.0) > _TOL:
            raise ValueError(f"{self.name}: b and b_hat must each sum to 1 (consistency)")
        if np.array_equal(b, b_hat):
            raise ValueError(f"{self.name}: b_hat equals b; no error estimate")
        if not np.allclose(dense.sum(axis=1), b, rtol=0.0, atol=_TOL):
            raise ValueError(f"{self.name}: dense output must reproduce b at θ = 1")
        if self.stiffly_accurate and not np.allclose(ai[-1], b, rtol=0.0, atol=_TOL):
            raise ValueError(f"{self.name}: stiffly accurate requires a_implicit[-1] = b")
        if not (int(self.order) >= 1 and int(self.error_order) >= 1):
            raise ValueError(f"{self.name}: orders must be positive integers")
        ew = b - b_hat
        ew.setflags(write=False)
        for name, value in (("a_explicit", ae), ("a_implicit", ai), ("c", c), ("b", b), ("b_hat", b_hat),
                            ("dense", dense), ("order", int(self.order)), ("error_order", int(self.error_order)),
                            ("gamma", gamma), ("error_weights", ew)):
            object.__setattr__(self, name, value)



def _fr(*xs: int | str) -> list[float]:
    return [float(Fraction(x)) for x in xs]


def _lower(rows: list[list[float]], s: int) -> np.ndarray:
    a = np.zeros((s, s))
    for i, r in enumerate(rows):
        a[i, : len(r)] = r
    return a


_G3 = "1767732205903/4055673282236"

#: K&C ARK3(2)4L[2]SA (their Tables 3–4 and the dense output of their §4.5).
ARK3_2_4L = AdditiveTableau(
    name="ark32",
    a_explicit=_lower([[], _fr("1767732205903/2027836641118"),
                       _fr("5535828885825/10492691773637", "788022342437/10882634858940"),
                       _fr("6485989280629/16251701735622", "-4246266847089/9704473918619",
                           "10755448449292/10357097424841")], 4),
    a_implicit=_lower([[], _fr(_G3, _G3),
                       _fr("2746238789719/10658868560708", "-640167445237/6845629431997", _G3),
                       _fr("1471266399579/7840856788654", "-4482444167858/7529755066697",
                           "11266239266428/11593286722821", _G3)], 4),
    c=_fr(0, "1767732205903/2027836641118", "3/5", 1),
    b=_fr("1471266399579/7840856788654", "-4482444167858/7529755066697", "11266239266428/11593286722821", _G3),
    b_hat=_fr("2756255671327/12835298489170", "-10771552573575/22201958757719", "9247589265047/10645013368117",
              "2193209047091/5459859503100"),
    order=3,
    error_order=2,
    dense=np.array([_fr("4655552711362/22874653954995", "-215264564351/13552729205753"),
                    _fr("-18682724506714/9892148508045", "17870216137069/13817060693119"),
                    _fr("34259539580243/13192909600954", "-28141676662227/17317692491321"),
                    _fr("584795268549/6622622206610", "2508943948391/7218656332882")]),
)

#: K&C ARK4(3)6L[2]SA (their Tables 5–6 and the dense output of their §4.5).
ARK4_3_6L = AdditiveTableau(
    name="ark43",
    a_explicit=_lower([[], _fr("1/2"), _fr("13861/62500", "6889/62500"),
                       _fr("-116923316275/2393684061468", "-2731218467317/15368042101831",
                           "9408046702089/11113171139209"),
                       _fr("-451086348788/2902428689909", "-2682348792572/7519795681897",
                           "12662868775082/11960479115383", "3355817975965/11060851509271"),
                       _fr("647845179188/3216320057751", "73281519250/8382639484533",
                           "552539513391/3454668386233", "3354512671639/8306763924573", "4040/17871")], 6),
    a_implicit=_lower([[], _fr("1/4", "1/4"), _fr("8611/62500", "-1743/31250", "1/4"),
                       _fr("5012029/34652500", "-654441/2922500", "174375/388108", "1/4"),
                       _fr("15267082809/155376265600", "-71443401/120774400", "730878875/902184768",
                           "2285395/8070912", "1/4"),
                       _fr("82889/524892", 0, "15625/83664", "69875/102672", "-2260/8211", "1/4")], 6),
    c=_fr(0, "1/2", "83/250", "31/50", "17/20", 1),
    b=_fr("82889/524892", 0, "15625/83664", "69875/102672", "-2260/8211", "1/4"),
    b_hat=_fr("4586570599/29645900160", 0, "178811875/945068544", "814220225/1159782912", "-3700637/11593932",
              "61727/225920"),
    order=4,
    error_order=3,
    dense=np.array([_fr("6943876665148/7220017795957", "-54480133/30881146", "6818779379841/7100303317025"),
                    _fr(0, 0, 0),
                    _fr("7640104374378/9702883013639", "-11436875/14766696", "2173542590792/12501825683035"),
                    _fr("-20649996744609/7521556579894", "174696575/18121608", "-31592104683404/5083833661969"),
                    _fr("8854892464581/2390941311638", "-12120380/966161", "61146701046299/7138195549469"),
                    _fr("-11397109935349/6675773540249", "3843/706", "-17219254887155/4939391667607")]),
)

IMEX_TABLEAUS: dict[str, AdditiveTableau] = {"ark32": ARK3_2_4L, "ark43": ARK4_3_6L}
