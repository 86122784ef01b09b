"""Embedded Runge–Kutta pairs as data: Butcher tableaus, validated on construction (see
:mod:`drillstring.dynamics.runge_kutta` for the methods, their order conditions and references).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

_TABLEAU_TOL = 1e-12


def _readonly(x: Any, ndim: int) -> np.ndarray:
    arr = np.array(x, dtype=np.float64)  # always a private copy
    if arr.ndim != ndim:
        raise ValueError(f"expected a {ndim}-D array, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


class EmbeddedPair:
    """What every embedded pair of this package's methods (explicit here, additive in
    :mod:`drillstring.dynamics.additive_rk`) answers from its validated arrays: nodes ``c``, orders ``order`` and
    ``error_order``."""

    @property
    def n_stages(self) -> int:
        return int(self.c.shape[0])

    @property
    def controller_order(self) -> int:
        """Order ``q`` of the local error estimate (the lower order of the pair); the controller uses
        exponents ``∝ 1/(q + 1)``."""
        return min(self.order, self.error_order)


@dataclass(frozen=True, eq=False)
class ButcherTableau(EmbeddedPair):
    """An explicit embedded Runge–Kutta pair as data.

    Attributes
    ----------
    name:
        Short name.
    c:
        Nodes, shape ``(s,)``.
    a:
        Stage coefficients, shape ``(s, s)``, strictly lower triangular.
    b:
        Weights of the propagated solution (the higher-order one, "local extrapolation").
    b_hat:
        Weights of the embedded solution; ``b − b_hat`` gives the error estimate.
    order:
        Order of ``b``.
    error_order:
        Order of ``b_hat``.
    fsal:
        "First same as last": the last stage is evaluated at the new solution (``c[-1] = 1`` and
        ``a[-1] = b``), so it is the next step's first stage.
    dense:
        Continuous-extension coefficients, shape ``(s, p)``: ``b_i(θ) = Σ_{j=1..p} dense[i, j−1] θ^j`` and
        ``y(t + θh) ≈ y + h Σ_i b_i(θ) k_i``; ``None`` when the tableau has none (the stepper then uses
        cubic Hermite interpolation).

    Construction checks the shapes, strict lower triangularity, ``Σ_j a_ij = c_i``, ``Σ b = Σ b_hat = 1``,
    the FSAL structure when claimed, and ``b_i(1) = b_i`` for the dense output. Arrays are stored as
    read-only copies.
    """

    name: str
    c: np.ndarray
    a: np.ndarray
    b: np.ndarray
    b_hat: np.ndarray
    order: int
    error_order: int
    fsal: bool = False
    dense: np.ndarray | None = None
    # derived (not init arguments)
    error_weights: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        c = _readonly(self.c, 1)
        a = _readonly(self.a, 2)
        b = _readonly(self.b, 1)
        b_hat = _readonly(self.b_hat, 1)
        s = c.shape[0]
        if s < 1 or a.shape != (s, s) or b.shape != (s,) or b_hat.shape != (s,):
            raise ValueError(
                f"{self.name}: inconsistent shapes c{c.shape}, a{a.shape}, b{b.shape}, b_hat{b_hat.shape}"
            )
        if np.any(np.triu(a) != 0.0):
            raise ValueError(f"{self.name}: `a` must be strictly lower triangular (explicit method)")
        if not np.allclose(a.sum(axis=1), c, rtol=0.0, atol=_TABLEAU_TOL):
            raise ValueError(f"{self.name}: row sums of `a` must equal `c`")
        if c[0] != 0.0:
            raise ValueError(f"{self.name}: c[0] must be 0 for an explicit method")
        if abs(b.sum() - 1.0) > _TABLEAU_TOL or abs(b_hat.sum() - 1.0) > _TABLEAU_TOL:
            raise ValueError(f"{self.name}: `b` and `b_hat` must each sum to 1 (consistency)")
        if np.array_equal(b, b_hat):
            raise ValueError(f"{self.name}: `b_hat` equals `b`; no error estimate")
        if not (int(self.order) >= 1 and int(self.error_order) >= 1):
            raise ValueError(f"{self.name}: orders must be positive integers")
        if self.fsal and (abs(c[-1] - 1.0) > _TABLEAU_TOL or not np.allclose(a[-1], b, rtol=0, atol=_TABLEAU_TOL)):
            raise ValueError(f"{self.name}: FSAL requires c[-1] = 1 and a[-1] = b")
        dense = None
        if self.dense is not None:
            dense = _readonly(self.dense, 2)
            if dense.shape[0] != s or dense.shape[1] < 1:
                raise ValueError(f"{self.name}: `dense` must have shape (s, p), got {dense.shape}")
            if not np.allclose(dense.sum(axis=1), b, rtol=0.0, atol=_TABLEAU_TOL):
                raise ValueError(f"{self.name}: dense output must reproduce `b` at θ = 1")
        ew = b - b_hat
        ew.setflags(write=False)
        for name, value in (("c", c), ("a", a), ("b", b), ("b_hat", b_hat), ("dense", dense),
                            ("order", int(self.order)), ("error_order", int(self.error_order)),
                            ("fsal", bool(self.fsal)), ("error_weights", ew)):
            object.__setattr__(self, name, value)


    def dense_weights(self, theta: float | np.ndarray) -> np.ndarray:
        """``b_i(θ)``, shape ``(s,)`` for scalar θ or ``(m, s)`` for an array of θ."""
        if self.dense is None:
            raise ValueError(f"{self.name} has no dense-output coefficients")
        return dense_weights(self.dense, theta)


def dense_weights(dense: np.ndarray, theta: float | np.ndarray) -> np.ndarray:
    """``b_i(θ) = Σ_p dense[i, p] θ^(p+1)`` of a continuous extension ``dense`` (s, p): shape ``(s,)`` for
    scalar θ or ``(m, s)`` for an array of θ."""
    th = np.asarray(theta, dtype=np.float64)
    powers = th[..., None] ** np.arange(1, dense.shape[1] + 1)
    return powers @ dense.T


def _fr(*xs: int | str) -> list[float]:
    return [float(Fraction(x)) for x in xs]


def _lower(rows: list[list[float]]) -> np.ndarray:
    s = len(rows)
    a = np.zeros((s, s))
    for i, r in enumerate(rows):
        a[i, : len(r)] = r
    return a


#: Dormand & Prince (1980) 5(4), FSAL, with Shampine's (1986) 4th-order continuous extension.
DORMAND_PRINCE_54 = ButcherTableau(
    name="dopri5",
    c=_fr(0, "1/5", "3/10", "4/5", "8/9", 1, 1),
    a=_lower(
        [
            [],
            _fr("1/5"),
            _fr("3/40", "9/40"),
            _fr("44/45", "-56/15", "32/9"),
            _fr("19372/6561", "-25360/2187", "64448/6561", "-212/729"),
            _fr("9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656"),
            _fr("35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84"),
        ]
    ),
    b=_fr("35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0),
    b_hat=_fr("5179/57600", 0, "7571/16695", "393/640", "-92097/339200", "187/2100", "1/40"),
    order=5,
    error_order=4,
    fsal=True,
    dense=np.array(
        [
            _fr(1, "-8048581381/2820520608", "8663915743/2820520608", "-12715105075/11282082432"),
            _fr(0, 0, 0, 0),
            _fr(0, "131558114200/32700410799", "-68118460800/10900136933", "87487479700/32700410799"),
            _fr(0, "-1754552775/470086768", "14199869525/1410260304", "-10690763975/1880347072"),
            _fr(0, "127303824393/49829197408", "-318862633887/49829197408", "701980252875/199316789632"),
            _fr(0, "-282668133/205662961", "2019193451/616988883", "-1453857185/822651844"),
            _fr(0, "40617522/29380423", "-110615467/29380423", "69997945/29380423"),
        ]
    ),
)

#: Bogacki & Shampine (1989) 3(2), FSAL, with its cubic Hermite continuous extension (module docstring).
BOGACKI_SHAMPINE_32 = ButcherTableau(
    name="bs32",
    c=_fr(0, "1/2", "3/4", 1),
    a=_lower([[], _fr("1/2"), _fr(0, "3/4"), _fr("2/9", "1/3", "4/9")]),
    b=_fr("2/9", "1/3", "4/9", 0),
    b_hat=_fr("7/24", "1/4", "1/3", "1/8"),
    order=3,
    error_order=2,
    fsal=True,
    dense=np.array(
        [
            _fr(1, "-4/3", "5/9"),
            _fr(0, 1, "-2/3"),
            _fr(0, "4/3", "-8/9"),
            _fr(0, -1, 1),
        ]
    ),
)

TABLEAUS: dict[str, ButcherTableau] = {"dopri5": DORMAND_PRINCE_54, "bs32": BOGACKI_SHAMPINE_32}

