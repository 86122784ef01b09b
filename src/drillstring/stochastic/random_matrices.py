"""Nonparametric model uncertainty: random reduced mass, damping and stiffness matrices.

Soize's nonparametric approach (Soize 2000, "A nonparametric model of random uncertainties for reduced
matrix models in structural dynamics", Probab. Eng. Mech. 15(3) 277–294; Soize 2005, "Random matrix theory
for modeling uncertainties in computational mechanics", Comput. Methods Appl. Mech. Engrg. 194, 1333–1366)
replaces each reduced matrix ``A`` (symmetric positive definite, ``n × n``) by a random matrix
``Ã = L G Lᵀ`` with ``A = L Lᵀ`` and ``G`` drawn from the ensemble SE+ of the Maximum-Entropy law of
symmetric positive-definite matrices under ``E{G} = I`` and ``E{ln det G}`` finite, with dispersion

    δ = ( E{‖G − I‖²_F} / ‖I‖²_F )^{1/2},       0 ≤ δ < δ_max(n) = ((n + 1) / (n + 5))^{1/2}

(the bound keeps ``E{‖G⁻¹‖²}`` finite). The construction implemented (Soize 2000 §5.3, 2005 §4.2):
``G = Hᵀ H``, ``H`` upper triangular with independent entries,

    H_jk = σ U_jk  (j < k),   U_jk standard normal,      H_jj = σ (2 V_j)^{1/2},
    V_j Gamma of shape (n + 1)/(2δ²) + (1 − j)/2 (j = 1..n) and scale 1,    σ = δ (n + 1)^{-1/2},

which gives ``E{G} = I`` and ``Var(G_jk) = δ² (1 + δ_jk) / (n + 1)``, hence the dispersion δ exactly.

A semi-definite ``A`` (a rigid mode's zero stiffness, an undamped family) is factored ``A = L Lᵀ`` with
``L`` of its rank ``r`` (``n × r``, the eigenvectors of the positive eigenvalues) and ``G`` of size ``r``
(Soize's ensemble SE+0 for a rank-deficient mean). Negative stiffness eigenvalues (a family prestressed
beyond buckling) are kept at their nominal values: the ensemble is of positive matrices.

The reduced model of :mod:`drillstring.dynamics.rom` is diagonal per mode family (mass ``I``, stiffness
``diag(ω²)``, damping ``D`` in family blocks). :func:`random_reduced_model` draws, per family independently
(block-diagonal, so the families stay uncoupled), ``M̃``, ``K̃``, ``D̃``, solves ``K̃ X = M̃ X Λ`` with
``Xᵀ M̃ X = I`` and folds ``X`` into the model: shapes ``Φ ← Φ X``, ``ω² ← Λ``, damping ``← Xᵀ D̃ X``,
constant generalised force ``g ← Xᵀ g``. With ``ξ = X q`` the random equations ``M̃ ξ̈ + D̃ ξ̇ + K̃ ξ = g +
Φᵀ f(Φ ξ)`` are exactly those of a reduced model of the same form in ``q``, so every kernel, observation and
stability analysis runs unchanged. All three dispersions 0 returns the nominal model itself.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "ModelDispersion",
    "dispersion_limit",
    "germ",
    "measured_dispersion",
    "model_generator",
    "random_matrix",
    "random_reduced_model",
    "random_reduced_model_with_transform",
]

#: The families drawn independently (the ROM's contiguous blocks; rigid_axial goes with axial).
FAMILIES = (("rigid_axial", "axial"), ("torsional",), ("lateral_y",), ("lateral_z",))

#: The spawn key that separates a realization's model stream from its parameter stream.
MODEL_STREAM = 1


def dispersion_limit(n: int) -> float:
    """δ_max(n) = ((n + 1)/(n + 5))^{1/2}: the SE+ ensemble of size ``n`` needs 0 ≤ δ < δ_max (Soize 2000)."""
    return math.sqrt((n + 1) / (n + 5))


def germ(n: int, dispersion: float, rng: np.random.Generator) -> np.ndarray:
    """One draw of the germ ``G`` (``n × n``) of the ensemble SE+ of dispersion ``dispersion`` (module
    docstring; Soize 2000 §5.3). ``dispersion = 0`` gives ``I`` without drawing."""
    delta = float(dispersion)
    if n == 0 or delta == 0.0:
        return np.eye(n)
    limit = dispersion_limit(n)
    if not 0.0 <= delta < limit:
        raise ValueError(f"dispersion = {delta:g}: must be in [0, {limit:.4g}) for a matrix of size {n}")
    sigma = delta / math.sqrt(n + 1)
    h = np.triu(sigma * rng.standard_normal((n, n)), 1)
    shapes = (n + 1) / (2.0 * delta**2) + (1.0 - np.arange(1, n + 1)) / 2.0
    h[np.diag_indices(n)] = sigma * np.sqrt(2.0 * rng.gamma(shapes))
    return h.T @ h


def measured_dispersion(draws: np.ndarray) -> float:
    """δ̂ = (mean ‖G − I‖²_F / n)^{1/2} of germ draws ``(N, n, n)``: the sample estimate of δ."""
    draws = np.asarray(draws, dtype=float)
    n = draws.shape[-1]
    return math.sqrt(float(np.mean(np.sum((draws - np.eye(n)) ** 2, axis=(-2, -1)))) / n)


def _factor(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(L, N)`` with ``matrix = L Lᵀ + N``: ``L`` (n × r) from the positive eigenvalues, ``N`` the part of
    the non-positive ones (kept nominal)."""
    values, vectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    scale = max(float(np.max(np.abs(values), initial=0.0)), 1e-300)
    positive = values > 1e-12 * scale
    factor = vectors[:, positive] * np.sqrt(values[positive])
    rest = (vectors[:, ~positive] * values[~positive]) @ vectors[:, ~positive].T
    return factor, rest


def random_matrix(matrix: np.ndarray, dispersion: float, rng: np.random.Generator) -> np.ndarray:
    """One draw of ``Ã = L G Lᵀ (+ the non-positive part)`` of mean ``matrix`` (symmetric) and dispersion
    ``dispersion`` of its germ (module docstring). ``dispersion = 0`` returns ``matrix`` unchanged."""
    matrix = np.asarray(matrix, dtype=float)
    if float(dispersion) == 0.0:
        return matrix
    factor, rest = _factor(matrix)
    g = germ(factor.shape[1], dispersion, rng)
    out = factor @ g @ factor.T + rest
    return 0.5 * (out + out.T)


@dataclass(frozen=True)
class ModelDispersion:
    """The dispersions δ_M, δ_K, δ_D [-] of the random reduced mass, stiffness and damping matrices (each in
    ``[0, δ_max(n))`` for the family sizes ``n`` of the model, :func:`dispersion_limit`); all zero: no model
    uncertainty. The ``[uncertainty.model]`` table of a case (keys ``mass_dispersion``,
    ``stiffness_dispersion``, ``damping_dispersion``)."""

    mass: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0

    KEYS = ("mass_dispersion", "stiffness_dispersion", "damping_dispersion")

    def __post_init__(self) -> None:
        for key, name in zip(self.KEYS, ("mass", "stiffness", "damping")):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not 0.0 <= value < 1.0:
                raise ValueError(f"uncertainty.model.{key} = {value!r}: must be a number in [0, 1) (and below "
                                 "sqrt((n+1)/(n+5)) for a family of n modes)")
            object.__setattr__(self, name, float(value))

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any]) -> ModelDispersion:
        """From ``{"mass_dispersion": δ_M, "stiffness_dispersion": δ_K, "damping_dispersion": δ_D}`` (any
        subset; missing ones 0)."""
        if not isinstance(mapping, Mapping):
            raise ValueError(f"uncertainty.model must be a table, got {type(mapping).__name__}")
        unknown = [k for k in mapping if k not in cls.KEYS]
        if unknown:
            raise ValueError(f"uncertainty.model.{unknown[0]}: unknown key; allowed: {', '.join(cls.KEYS)}")
        return cls(*(mapping.get(k, 0.0) for k in cls.KEYS))

    @classmethod
    def from_tuple(cls, values) -> ModelDispersion:
        """From ``(δ_M, δ_K, δ_D)`` (a settings field; ValueError naming ``model_dispersion`` otherwise)."""
        values = tuple(values)
        if len(values) != 3:
            raise ValueError(f"model_dispersion = {values!r}: must be (mass, stiffness, damping) dispersions")
        return cls(*values)

    @classmethod
    def declared(cls, case, model: Mapping[str, Any] | None = None) -> ModelDispersion:
        """``model`` when given, else the case's ``[uncertainty.model]`` table, else none (all zero)."""
        if model is None and case.uncertainty is not None and case.uncertainty.model is not None:
            model = case.uncertainty.model.model_dump()
        return cls.from_mapping(model or {})

    def as_tuple(self) -> tuple[float, float, float]:
        """``(δ_M, δ_K, δ_D)``."""
        return (self.mass, self.stiffness, self.damping)

    def check_model(self, model, field: str | None = None) -> None:
        """:meth:`check` against the germ sizes of each family of a reduced model: its columns (mass), its
        positive ω² (stiffness) and the rank of its damping block (nothing when no dispersion is positive);
        ``field``: the name the error gives the dispersion (default ``uncertainty.model.<key>``)."""
        if not self.active:
            return
        sizes = {}
        for family, c in family_columns(model).items():
            rank = _factor(model.damping[np.ix_(c, c)])[0].shape[1] if self.damping > 0.0 else len(c)
            sizes[family] = (len(c), int(np.sum(model.omega2[c] > 0.0)), rank)
        self.check(sizes, field)

    def to_mapping(self) -> dict[str, float]:
        return dict(zip(self.KEYS, (self.mass, self.stiffness, self.damping)))

    @property
    def active(self) -> bool:
        """True when any dispersion is positive."""
        return self.mass > 0.0 or self.stiffness > 0.0 or self.damping > 0.0

    def check(self, sizes: Mapping[str, int | tuple[int, int, int]], field: str | None = None) -> None:
        """Refuse (ValueError naming the field, its value and the range) a dispersion at or above δ_max(n) of
        its germ of size ``n`` (``sizes``: family -> its number of modes, or the germ sizes ``(mass,
        stiffness, damping)`` of the family); ``field``: the field's name in the error (default
        ``uncertainty.model.<key>``)."""
        for j, (key, value) in enumerate(self.to_mapping().items()):
            for family, size in sizes.items():
                n = size if isinstance(size, int) else size[j]
                if value > 0.0 and n > 0 and value >= dispersion_limit(n):
                    name = field or f"uncertainty.model.{key}"
                    raise ValueError(
                        f"{name} = {value:g}: must be in [0, {dispersion_limit(n):.4g}) = "
                        f"[0, sqrt((n+1)/(n+5))) for the {family} family of n = {n} modes")


def model_generator(seed: int, index: int) -> np.random.Generator:
    """The random stream of the model matrices of realization ``index`` of a study seeded ``seed``:
    ``SeedSequence(seed, spawn_key=(index, MODEL_STREAM))``, independent of the parameters' stream
    (:func:`~drillstring.stochastic.maxent.realization_generator`); depends only on ``(seed, index)``."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(int(index),
                                                                                            MODEL_STREAM))))


def family_columns(model) -> dict[str, np.ndarray]:
    """The basis columns of each family of :data:`FAMILIES` (named by its last label) in ``model``."""
    labels = np.array(model.family)
    return {names[-1]: np.nonzero(np.isin(labels, names))[0] for names in FAMILIES}


def random_reduced_model(model, dispersion: ModelDispersion, rng: np.random.Generator):
    """:func:`random_reduced_model_with_transform` without the transform: the realized model alone."""
    return random_reduced_model_with_transform(model, dispersion, rng)[0]


def random_reduced_model_with_transform(model, dispersion: ModelDispersion, rng: np.random.Generator):
    """``(realized, X)``: a realization of ``model`` (:class:`~drillstring.dynamics.rom.ReducedOrderModel`) with random reduced
    mass, stiffness and damping matrices of dispersions ``dispersion``, drawn family by family from ``rng``
    (module docstring), and the block-diagonal ``X`` (n × n) that takes the realized model's coordinates to the
    nominal model's, ``ξ = X q`` (the realized basis is ``model.basis @ X``; a state of the realized model
    ``[q, q̇, s]`` is ``[X q, X q̇, s]`` in the nominal one). Returns ``(model, I)`` when no dispersion is
    positive.

    The damping matrix must be block diagonal by family (as every ROM built here is). The realized model has
    the same families, sizes and column order; within a family the columns are the realized modes in
    increasing ω² (a rigid mode, of zero stiffness, stays first and pure). ``residual_columns`` keeps its
    positions (the attachment columns, highest in their family, stay last; once the random mass mixes them
    with the modes, the flag is an approximation); ``modes`` stays the nominal modal analysis. A top drive's
    rigid rotation stays the first torsional column with ω = 0.
    """
    if not dispersion.active:
        return model, np.eye(len(model.angular_frequencies))
    columns = family_columns(model)
    dispersion.check_model(model)
    n = len(model.angular_frequencies)
    inside = np.zeros((n, n), dtype=bool)
    for c in columns.values():
        inside[np.ix_(c, c)] = True
    if np.any(model.damping[~inside] != 0.0):
        raise ValueError("random_reduced_model: the damping matrix couples two families; the random matrices "
                         "are drawn family by family")
    basis = model.basis.copy()
    omega2 = model.omega2.copy()
    damping = np.zeros_like(model.damping)
    force = np.array(model.generalized_force, dtype=float)
    transform = np.zeros((n, n))
    for c in columns.values():
        if not len(c):
            continue
        block = np.ix_(c, c)
        mass = random_matrix(np.eye(len(c)), dispersion.mass, rng)
        stiffness = random_matrix(np.diag(model.omega2[c]), dispersion.stiffness, rng)
        damp = random_matrix(model.damping[block], dispersion.damping, rng)
        values, x = _generalized_eigh(stiffness, mass)
        basis[:, c] = model.basis[:, c] @ x
        omega2[c] = values
        damping[block] = x.T @ damp @ x
        force[c] = x.T @ force[c]
        transform[block] = x
    omega = np.sign(omega2) * np.sqrt(np.abs(omega2))
    return dataclasses.replace(model, basis=basis, angular_frequencies=omega, damping=damping,
                               generalized_force=force, residual_columns=model.residual_columns.copy()), transform


def _generalized_eigh(stiffness: np.ndarray, mass: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """λ, X of ``K X = M X diag(λ)`` with ``Xᵀ M X = I`` (M positive definite), λ increasing; a column's sign
    is fixed so that its largest entry is positive (a realization does not depend on LAPACK's choice)."""
    from scipy import linalg

    values, x = linalg.eigh(stiffness, mass)
    values[np.abs(values) <= 1e-12 * max(float(np.max(np.abs(values), initial=0.0)), 1e-300)] = 0.0
    pivot = np.argmax(np.abs(x), axis=0)
    x *= np.sign(x[pivot, np.arange(x.shape[1])])
    return values, x
