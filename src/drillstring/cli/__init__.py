"""The ``drillstring`` command line (Typer): a package of command modules sharing one set of options.

Commands
--------
``drillstring static [CASE] [--json]``
    The prestressed static state: weight, weight-on-hook, weight-on-bit, neutral point, critical
    weight-on-bit (lateral buckling), axial force.
``drillstring modes [CASE] [--count N] [--json]``
    The lowest natural frequencies of the axial, torsional and lateral mode families.
``drillstring campbell [CASE] [--top-speed A:B:N] [--blades N] [--plot FILE.png] [--json]``
    Campbell diagram: frequencies of each family against rotary speed, excitation lines, critical speeds.
``drillstring cases``
    The built-in cases.
``drillstring simulate [CASE] [--t-end S] [--out FILE.nc] [--plot FILE.png] [--json]``
    One drilling run: NetCDF of the observables, a six-panel figure and a summary table.
``drillstring study [CASE] [--param PATH=LAW ...] [--sigma N | --dispersion D] [--samples N] [--out DIR] ...``
    Monte Carlo study of random case parameters (default: the weight-on-hook): Zarr store (resumable),
    statistics, figures, report.
``drillstring map [CASE] [--top-speed A:B:N] [--weight-on-bit A:B:N] [--t-end S] [--out DIR] ...``
    Operating map over top speed × weight-on-bit: performance, vibration, stability, buckling margin;
    with ``--samples N`` (and ``--sigma``/``--param``), probabilities of stick-slip, buckling, impact and
    instability at each point.
``drillstring sensitivity [CASE] --param PATH=LAW ... [--samples N] [--out DIR] ...``
    Global sensitivity: Sobol' indices of ROP, vibration, TOB, FOB.
``drillstring compare [CASE] [--t-end S] [--plot FILE.png] [--json]``
    Case 1 (full nonlinear model) against case 2 (bit–rock + contact): differences, wall times, figure.
``drillstring torque-drag [CASE] [--json] [--plot FILE.png] [--measurements CSV] [--html FILE]``
    Soft-string torque and drag along the well of the case's ``[well]`` survey: hook load and surface torque
    tripping out and in, rotating off bottom, sliding and drilling; buckling; lock-up; friction calibration.
``drillstring estimate [CASE] [--surface CSV] [--truth CSV] [--out DIR] [--ensemble-size N] [--json]``
    The downhole state (bit speed, torque and force on bit, ROP, stick-slip index) and the bit–rock coefficient
    and weight-on-bit bias in time, with 5–95 % bands, from a surface record (an ensemble Kalman filter).

``CASE`` is a built-in case name (default ``reference``) or the path to a TOML case file.

Conventions for every command (follow them when adding one)
------------------------------------------------------------
- A command lives in the module of its group and takes the shared options of :mod:`~drillstring.cli.options`
  (``CaseArg``, ``JsonOpt``, ``UnitsOpt``, ``ParamOption``, ``OutOption``, ...); import the module here, in
  the order of ``--help``.
- Load the case with :func:`~drillstring.cli.options._load`: an invalid case prints its message to stderr and
  exits with code 2.
- Print a table with :func:`~drillstring.cli.tables.print_table`, never ``console.print(table)``: at 80
  columns and below it wraps or narrows the table and never cuts a number or a header with ``…``.
- Physics stays out of this module: a command calls the package API and only formats the result.
- ``--json`` prints ``json.dumps(payload, indent=2)`` of SI values, and nothing else, on stdout.
- Human-readable output (rich tables) converts units here, at the edge, into the unit system of the shared
  ``--units`` option (:data:`UnitsOpt`, every command that prints tables or draws figures has it): ``si``
  (kN, m, m/h, kN·m, mm) or ``field`` (klbf, ft, ft/h, kft·lbf, in); frequencies in Hz and speeds in rpm in
  both (:mod:`drillstring.units`). JSON stays SI.
- Progress bars and notes go to stderr, so that stdout holds only the table or the JSON.
- Exit codes: 0 success, 1 a run that failed, 2 invalid input, 130 interrupted (Ctrl-C).
- Heavy modules (SciPy, simulation, Monte Carlo, xarray, Matplotlib) are imported inside the commands
  that need them, so that each command loads only what it uses.
- Every dense linear-algebra problem of a command is small (a few hundred DOFs per mode family), so BLAS
  runs single-threaded here unless the environment says otherwise: its threads only add synchronisation
  (a 2-core machine under load computed the modes 4-40x slower with two threads).

Modules
-------
:mod:`~drillstring.cli.options` (the application ``app``, shared options and helpers),
:mod:`~drillstring.cli.tables` (tables that fit the terminal), :mod:`~drillstring.cli.engine` (what the
engine commands share), and one module per command group: ``static`` (cases, static, modes), ``campbell``,
``stability``, ``simulate`` (simulate, compare), ``study``, ``operating_map``, ``sensitivity``,
``optimize``, ``torque_drag``, ``estimate``.
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # before NumPy loads BLAS (see the module docstring)

# The command modules register their commands on ``app`` when imported, in the order of ``--help``.
from drillstring.cli import (  # noqa: E402, F401
    static,
    campbell,
    stability,
    simulate,
    study,
    operating_map,
    sensitivity,
    optimize,
    torque_drag,
    estimate,
)
from drillstring.cli.options import (  # noqa: E402, F401
    EXIT_INTERRUPTED,
    EXIT_INVALID_INPUT,
    EXIT_RUN_FAILED,
    CaseArg,
    JsonOpt,
    UnitsOpt,
    app,
)
from drillstring.cli.study import _realizations_table, _study_table  # noqa: E402, F401

#: Commands that run in their own process only and never use Dask. With Dask installed, xarray imports
#: dask.array and dask.distributed (about 0.4 s of start-up) for ordinary Dataset operations and NetCDF
#: writes; the console script hides Dask from these commands so that xarray treats it as absent.
#: (``study``, ``map`` and ``sensitivity`` may run on a Dask cluster and keep it.)
NO_DASK_COMMANDS = frozenset({"cases", "static", "modes", "stability", "simulate", "compare", "torque-drag",
                              "estimate"})


def run() -> None:
    """The ``drillstring`` console script: :data:`app`, with Dask hidden from the commands that do not
    use it (:data:`NO_DASK_COMMANDS`). Only the console script does this: a process that imports the
    package (a notebook, the tests) keeps Dask."""
    import sys

    command = next((arg for arg in sys.argv[1:] if not arg.startswith("-")), None)
    if command in NO_DASK_COMMANDS and "dask" not in sys.modules:
        sys.modules["dask"] = None  # `import dask` raises ImportError, find_spec("dask") is None
    app()

