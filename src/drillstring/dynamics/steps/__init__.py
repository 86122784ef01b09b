"""Steps of the compiled integrator, one module per kind, the loop (:mod:`drillstring.dynamics.compiled`)
generic over them: :mod:`.kinds` (what a kind provides, the registry), :mod:`.explicit_rk` (explicit embedded
Runge–Kutta pairs), :mod:`.imex_ark` (implicit–explicit additive Runge–Kutta pairs, the stiff part implicit), :mod:`.exponential`
(exponential Runge–Kutta pairs, the linear modal part exact)."""

from drillstring.dynamics.steps import explicit_rk  # noqa: F401  (registers the explicit Runge–Kutta step)
from drillstring.dynamics.steps import imex_ark  # noqa: F401  (registers the implicit–explicit step)
from drillstring.dynamics.steps import exponential  # noqa: F401  (registers the exponential step)
from drillstring.dynamics.steps.kinds import StepKind, accept, attempt, kind_of, register, step_data

__all__ = ["StepKind", "accept", "attempt", "kind_of", "register", "step_data"]
