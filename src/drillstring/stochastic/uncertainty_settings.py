"""The uncertainty of a stochastic computation, one settings object shared by Monte Carlo studies
(:class:`~drillstring.stochastic.montecarlo.StudySettings`), probabilistic maps
(:class:`~drillstring.stochastic.probabilistic_map.SampledMapSettings`), the optimiser
(:class:`~drillstring.stochastic.optimize.OptimizationSettings`) and sensitivity runs
(:class:`~drillstring.stochastic.sensitivity_study.SensitivitySettings`).

:class:`UncertaintySettings` holds what is random, validated once: the parametric laws ``((path, spec), ...)``
(:mod:`~drillstring.stochastic.uncertainty`), the correlation matrix of some normal parameters, and the model
dispersion ``(δ_M, δ_K, δ_D)`` of the random reduced matrices (:mod:`~drillstring.stochastic.random_matrices`).
:meth:`UncertaintySettings.law` builds the joint law (:class:`~drillstring.stochastic.uncertainty.Uncertainty`)
on a case. The settings classes hold it as their field ``uncertainty`` and, through
:func:`accepts_uncertainty_fields`, still accept (and expose) the flat keywords ``laws``, ``correlated``,
``correlation`` and ``model_dispersion``; :meth:`UncertaintyFields.store_settings` gives the flat dictionary their
stores fingerprint (:func:`~drillstring.stochastic.store.fingerprint`), unchanged by the composition, so a store
written before it resumes.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass
from collections.abc import Mapping
from typing import Any

from drillstring.case import Case
from drillstring.stochastic.random_matrices import ModelDispersion
from drillstring.stochastic.uncertainty import Uncertainty, uncertainty

__all__ = ["NO_UNCERTAINTY", "UNCERTAINTY_FIELDS", "UncertaintyFields", "UncertaintySettings",
           "accepts_uncertainty_fields"]

#: The fields of :class:`UncertaintySettings`, also accepted as keywords by the settings that hold one.
UNCERTAINTY_FIELDS = ("laws", "correlated", "correlation", "model_dispersion")


@dataclass(frozen=True)
class UncertaintySettings:
    """What is random in a stochastic computation (canonical, hashable, picklable).

    Attributes:
        laws: ``((path, spec), ...)`` of the random case parameters, in order (case-parameter paths, e.g.
            ``weight_on_hook`` or ``fluid.inlet_velocity``, and law specs, :mod:`~drillstring.stochastic.
            uncertainty`); paths stripped, each at most once.
        correlated: paths of the correlated normal parameters (empty: independent).
        correlation: their correlation matrix, ``len(correlated)`` rows of ``len(correlated)`` finite numbers
            (symmetry, unit diagonal and positive definiteness are checked with the laws, by :meth:`law`).
        model_dispersion: ``(δ_M, δ_K, δ_D)`` [-] of the random reduced mass, stiffness and damping matrices
            (all 0: no model uncertainty).

    Checked when built: TypeError / ValueError naming the field, its value and what is allowed.
    """

    laws: tuple[tuple[str, str], ...] = ()
    correlated: tuple[str, ...] = ()
    correlation: tuple[tuple[float, ...], ...] = ()
    model_dispersion: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        laws = []
        for i, item in enumerate(_sequence("laws", self.laws)):
            if isinstance(item, (str, bytes)) or not hasattr(item, "__len__") or len(item) != 2:
                raise ValueError(f"laws[{i}] = {item!r}: must be a (path, law spec) pair, e.g. "
                                 "('weight_on_hook', 'normal 150e3 5e3')")
            path, spec = str(item[0]).strip(), str(item[1])
            if not path:
                raise ValueError(f"laws[{i}] = {item!r}: the path is empty (a case-parameter path is required)")
            if path in (p for p, _ in laws):
                raise ValueError(f"{path} is declared twice in laws (each parameter has one law)")
            laws.append((path, spec))
        correlated = tuple(str(p).strip() for p in _sequence("correlated", self.correlated))
        twice = next((p for i, p in enumerate(correlated) if p in correlated[:i]), None)
        if twice is not None:
            raise ValueError(f"correlated: {twice} is listed twice (each correlated parameter once)")
        rows = _sequence("correlation", self.correlation)
        if bool(correlated) != bool(rows):
            raise ValueError(f"correlated = {correlated!r}, correlation with {len(rows)} rows: give both the "
                             "correlated parameters and their correlation matrix, or neither")
        matrix = []
        for i, row in enumerate(rows):
            row = _sequence(f"correlation[{i}]", row)
            if len(row) != len(correlated):
                raise ValueError(f"correlation[{i}] has {len(row)} entries: must have {len(correlated)}, one per "
                                 f"correlated parameter ({', '.join(correlated)})")
            try:
                values = tuple(float(v) for v in row)
            except (TypeError, ValueError):
                raise ValueError(f"correlation[{i}] = {row!r}: must be numbers") from None
            if not all(math.isfinite(v) for v in values):
                raise ValueError(f"correlation[{i}] = {values!r}: must be finite numbers in [-1, 1]")
            matrix.append(values)
        if len(matrix) != len(correlated):
            raise ValueError(f"correlation has {len(matrix)} rows: must have {len(correlated)}, one per correlated "
                             f"parameter ({', '.join(correlated)})")
        object.__setattr__(self, "laws", tuple(laws))
        object.__setattr__(self, "correlated", correlated)
        object.__setattr__(self, "correlation", tuple(matrix))
        object.__setattr__(self, "model_dispersion", ModelDispersion.from_tuple(self.model_dispersion).as_tuple())

    @classmethod
    def of(cls, declared: Uncertainty | None,
           model_dispersion: ModelDispersion | tuple[float, float, float] = (0.0, 0.0, 0.0)) -> UncertaintySettings:
        """The settings of a declared joint law (:func:`~drillstring.stochastic.uncertainty.declared_uncertainty`;
        None: no random parameter): its parameters' canonical law specs in order, its correlated parameters and
        correlation matrix when not independent, and ``model_dispersion``."""
        if isinstance(model_dispersion, ModelDispersion):
            model_dispersion = model_dispersion.as_tuple()
        if declared is None:
            return cls(model_dispersion=model_dispersion)
        correlated, matrix = (), ()
        if declared.correlation is not None:
            correlated, matrix = declared.correlated, tuple(map(tuple, declared.correlation.tolist()))
        return cls(tuple((p.path, p.law.to_spec()) for p in declared.parameters), correlated, matrix,
                   model_dispersion)

    @property
    def model(self) -> ModelDispersion:
        """The model uncertainty (:class:`~drillstring.stochastic.random_matrices.ModelDispersion`)."""
        return ModelDispersion(*self.model_dispersion)

    @property
    def paths(self) -> tuple[str, ...]:
        """The paths of :attr:`laws`, in order."""
        return tuple(path for path, _ in self.laws)

    def law(self, case: Case, *, first: Mapping[str, str] | None = None, tolerance: float = 1.0) -> Uncertainty:
        """The joint law of the random parameters on ``case``: the laws of ``first`` (e.g. a map point's
        weight-on-hook Normal), then :attr:`laws`, with the correlation when declared.

        ``tolerance``: the largest probability a law may put outside its parameter's range (1 accepts any law;
        draws outside fail their realization). Raises :class:`~drillstring.stochastic.parameters.
        ParameterError` (one line) for an unknown path, a bad law or correlation, a law beyond ``tolerance``,
        and a path of ``first`` also in :attr:`laws`."""
        from drillstring.stochastic.parameters import ParameterError

        laws = dict(first or {})
        twice = next((path for path in self.paths if path in laws), None)
        if twice is not None:
            raise ParameterError(f"{twice} is declared twice")
        laws.update(dict(self.laws))
        correlation = [list(row) for row in self.correlation] if self.correlated else None
        return uncertainty(case, laws, correlated=self.correlated, correlation=correlation, tolerance=tolerance)


def _sequence(name: str, value: Any) -> tuple:
    """``value`` as a tuple (TypeError naming the field for a string or a non-sequence)."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise TypeError(f"{name} = {value!r}: must be a sequence")
    return tuple(value)


#: No random parameter and no model dispersion (the default ``uncertainty`` of the settings that hold one).
NO_UNCERTAINTY = UncertaintySettings()


class UncertaintyFields:
    """Mixin of a settings dataclass holding an :class:`UncertaintySettings` as its field ``uncertainty``: the
    uncertainty's fields read through (``settings.laws`` ...), and the flat dictionary of its stores."""

    uncertainty: UncertaintySettings

    @property
    def laws(self) -> tuple[tuple[str, str], ...]:
        return self.uncertainty.laws

    @property
    def correlated(self) -> tuple[str, ...]:
        return self.uncertainty.correlated

    @property
    def correlation(self) -> tuple[tuple[float, ...], ...]:
        return self.uncertainty.correlation

    @property
    def model_dispersion(self) -> tuple[float, float, float]:
        return self.uncertainty.model_dispersion

    @property
    def model(self) -> ModelDispersion:
        """The model uncertainty (:class:`~drillstring.stochastic.random_matrices.ModelDispersion`)."""
        return self.uncertainty.model

    def store_settings(self, fields: tuple[str, ...] = UNCERTAINTY_FIELDS) -> dict[str, Any]:
        """The settings as the flat dictionary their store keeps and fingerprints: the other fields (as
        :func:`dataclasses.asdict`), then the uncertainty's ``fields`` in place of ``uncertainty`` — the
        dictionary these settings had before the uncertainty was one object, so old stores resume."""
        flat = asdict(self)  # type: ignore[call-overload]
        nested = flat.pop("uncertainty")
        flat.update({name: nested[name] for name in fields})
        return flat

    def _check_uncertainty(self) -> None:
        if not isinstance(self.uncertainty, UncertaintySettings):
            raise TypeError(f"uncertainty = {self.uncertainty!r}: must be an UncertaintySettings")


def accepts_uncertainty_fields(cls):
    """Class decorator of a settings dataclass with a field ``uncertainty``: its constructor also accepts the
    fields of :class:`UncertaintySettings` as keywords (``laws=..., model_dispersion=...``, the settings'
    earlier signature), gathered into ``uncertainty``; giving both is refused (ValueError naming them)."""
    init = cls.__init__

    @functools.wraps(init)
    def __init__(self, *args, **kwargs):
        flat = {name: kwargs.pop(name) for name in UNCERTAINTY_FIELDS if name in kwargs}
        if flat:
            if kwargs.get("uncertainty") is not None:
                raise ValueError(f"uncertainty and {', '.join(flat)}: give the UncertaintySettings or its fields, "
                                 "not both")
            kwargs["uncertainty"] = UncertaintySettings(**flat)
        init(self, *args, **kwargs)

    cls.__init__ = __init__
    return cls
