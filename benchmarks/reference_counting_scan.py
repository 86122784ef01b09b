"""The compiled kernels of the package that return arrays, after a cold compilation of every kind of run
(tests/dynamics/test_reference_counting.py says why none may, through a call, since the loops run without
Numba's reference counting). Run in a fresh kernel cache, so that every kernel is compiled in this process:

    NUMBA_CACHE_DIR=$(mktemp -d) .venv/bin/python benchmarks/reference_counting_scan.py

Prints each compiled overload whose return type holds an array, marked "inlined" for the implementations that
Numba inlines into their callers (``inline="always"``: what they return crosses no call), and exits with 1 when
another one is found. About 2 min of compilation.
"""

from __future__ import annotations

import gc
import sys

import numba
from numba.core import types

from drillstring.api import simulate
from drillstring.case import load_case

#: Inlined into their compiled callers (``inline="always"``); compiled alone only for typing or from Python.
INLINED = ("drillstring.dynamics.delay.view", "drillstring.dynamics.reduced.rhs._stiff_part_compiled.<locals>.")

RUNS = (("reference", {}), ("contact", {}), ("stick_slip", {}), ("motor", {}), ("aarsnes2019", {"method": "dopri5"}),
        ("aarsnes2019", {"method": "ark43"}), ("reference", {"method": "ark32"}), ("reference", {"method": "erk32"}),
        ("reference", {"nonlinear": "full"}), ("reference", {"nonlinear": "full", "method": "ark43"}))


def _holds_arrays(kind) -> bool:
    if isinstance(kind, types.ArrayCompatible):
        return True
    if isinstance(kind, types.BaseTuple):
        return any(_holds_arrays(member) for member in kind.types)
    return False


def main() -> int:
    for name, changes in RUNS:
        case = load_case(name)
        model = case.model.model_copy(update={k: v for k, v in changes.items() if k == "nonlinear"})
        simulation = case.simulation.model_copy(update={"t_end": 0.05,
                                                        **{k: v for k, v in changes.items() if k == "method"}})
        simulate(case.model_copy(update={"model": model, "simulation": simulation}))
        print(f"ran {name} {changes}", flush=True)
    found = 0
    for dispatcher in gc.get_objects():
        if not isinstance(dispatcher, numba.core.dispatcher.Dispatcher):
            continue
        name = f"{getattr(dispatcher.py_func, '__module__', '')}.{dispatcher.py_func.__qualname__}"
        if not name.startswith("drillstring"):
            continue
        for result in dispatcher.overloads.values():
            if _holds_arrays(result.signature.return_type):
                inlined = name.startswith(INLINED)
                found += not inlined
                print(f"{'inlined ' if inlined else 'RETURNS '} {name} -> {result.signature.return_type}")
    print(f"{found} kernel(s) returning arrays through a call")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
