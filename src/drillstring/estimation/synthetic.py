"""A synthetic field record with its hidden truth: what an estimator is tested on (issue 36, item 4;
docs/estimation.md, "Surface records").

The record is made by a model that is **not** the estimator's: a random-matrix realization
(:mod:`drillstring.stochastic.random_matrices`, dispersions δ_M = δ_K = δ_D = :data:`DISPERSION`) of the case's
reduced model with its own top drive (case 2, ``model.nonlinear = "bit_and_contact"``). The full nonlinear
model (case 1) was the first choice, but it does not take a top drive yet (the case is refused: "a top drive
needs model.nonlinear = bit_and_contact"), and a record with the top speed imposed would show no top-drive
dynamics at all.

The run starts on bottom (the case's start), is integrated to ``transient + duration`` [s] and sampled every
``sample_step`` [s] (the solver lands on each sample); the record keeps the samples after ``transient``, its
time from 0. Surface channels (true values):

- ``top_speed``: the ``quill_speed`` observable [rad/s];
- ``surface_torque``: the ``surface_torque`` observable [N·m];
- ``hook_load``: prescribed by the model: the static hook load (``model.static.weight_on_hook``, the weight
  less the weight on bit) less the hook-load component's extra force (none for an on-bottom start) [N];
- ``block_position``: :data:`BLOCK_START` [m] less the top's axial displacement ``φ_u(top) η`` read from the
  state at each sample (x points down) [m].

Measured = true + white Gaussian noise of :data:`NOISE` (standard deviations, SI), + :data:`HOOK_LOAD_BIAS` on
the hook load, written in :data:`FILE_UNITS` with :data:`DECIMALS`; the faults of :data:`FAULTS` are put at
fixed times of the record (those within its duration). The hidden truth holds, on the regular time axis (gap
samples included), the true surface channels, the downhole ones (``bit_speed``, ``torque_on_bit``,
``force_on_bit``, ``rate_of_penetration``, ``bit_depth``) and the fault put at each sample of each channel
(the codes of :data:`~drillstring.estimation.surface.FLAGS`), after ``#`` lines giving the parameters (the
case's bit–rock coefficients, the bias, the noise levels, the seed).

The random streams (model matrices, each channel's noise) are drawn from ``numpy.random.SeedSequence(seed)``
so that a shorter record is the start of a longer one with the same seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drillstring.estimation.surface import FROZEN, MISSING, SPIKE

__all__ = ["BLOCK_START", "DECIMALS", "DISPERSION", "FAULTS", "FILE_UNITS", "HOOK_LOAD_BIAS", "NOISE",
           "SEED", "SyntheticRecord", "make_synthetic_record", "read_truth", "write_synthetic_record"]

#: The seed of the shipped record.
SEED = 36
#: Dispersion of the random reduced mass, stiffness and damping matrices [-].
DISPERSION = 0.1
#: Sensor noise, standard deviations [SI]: 0.2 rpm, 200 N·m, 1 kN, 5 mm.
NOISE = {"top_speed": 0.2 * math.pi / 30.0, "surface_torque": 200.0, "hook_load": 1000.0, "block_position": 0.005}
#: Bias of the hook-load sensor [N].
HOOK_LOAD_BIAS = 2000.0
#: The block's height at t = 0 of the run [m].
BLOCK_START = 30.0
#: Column name and unit of each channel in the file, and the time's.
FILE_COLUMNS = {"time": ("TIME", "s"), "top_speed": ("RPM", "rpm"), "surface_torque": ("STOR", "kN*m"),
                "hook_load": ("HKLD", "kN"), "block_position": ("BPOS", "m")}
FILE_UNITS = {name: unit for name, (_, unit) in FILE_COLUMNS.items()}
#: Decimals written of each column (below the noise: 0.01 rpm, 0.1 N·m, 1 N, 0.1 mm).
DECIMALS = {"time": 2, "top_speed": 2, "surface_torque": 4, "hook_load": 3, "block_position": 4}
#: The faults put in the record: (kind, channel or "all", first time [s], last time [s], detail).
#: ``empty``: empty cells; ``null``: the LAS null value -999.25; ``gap``: rows removed; ``spike``: one sample
#: offset by ``detail`` [SI]; ``frozen``: the channel repeats its value at the first time until the last.
FAULTS = (
    ("empty", "surface_torque", 2.0, 2.1, None),
    ("gap", "all", 12.0, 13.4, None),
    ("null", "block_position", 21.5, 21.5, None),
    ("spike", "hook_load", 33.3, 33.3, -60e3),
    ("gap", "all", 47.0, 47.6, None),
    ("frozen", "top_speed", 58.0, 60.9, None),
)
#: The downhole observables kept in the truth.
DOWNHOLE = ("bit_speed", "torque_on_bit", "force_on_bit", "rate_of_penetration", "bit_depth")
_SI = {"top_speed": "rad/s", "surface_torque": "N*m", "hook_load": "N", "block_position": "m", "bit_speed": "rad/s",
       "torque_on_bit": "N*m", "force_on_bit": "N", "rate_of_penetration": "m/s", "bit_depth": "m"}


@dataclass(frozen=True)
class SyntheticRecord:
    """A synthetic record and its truth (module docstring).

    Attributes:
        time: the regular time axis [s] from the record's start (gap samples included).
        measured: channel -> measured values [SI] on ``time`` (NaN where missing, faults in).
        present: True where a sample is a row of the file (False in the gaps).
        truth: name -> true values [SI] on ``time``: the surface channels and :data:`DOWNHOLE`.
        faults: channel -> int8 codes of the fault put at each sample (0 none).
        parameters: name -> (value, unit, what).
        null: channel -> mask of the samples written as -999.25.
    """

    time: np.ndarray
    measured: dict[str, np.ndarray]
    present: np.ndarray
    truth: dict[str, np.ndarray]
    faults: dict[str, np.ndarray]
    parameters: dict[str, tuple[float | str, str, str]]
    null: dict[str, np.ndarray] = field(default_factory=dict)


def _sample_run(case, seed: int, t_end: float, sample_step: float, dispersion: float):
    """Times [s], observables and the top's axial displacement of the realized model, sampled."""
    from drillstring.dynamics.compiled import RunState, SolverSettings, advance
    from drillstring.dynamics.reduced.observation import OBSERVABLE_COLUMN
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.stochastic.random_matrices import ModelDispersion, random_reduced_model

    nominal = case_reduced_model(case)
    stream = np.random.SeedSequence(int(seed)).spawn(1)[0]
    model = random_reduced_model(nominal, ModelDispersion(dispersion, dispersion, dispersion),
                                 np.random.default_rng(stream))
    n = len(model.angular_frequencies)
    s = case.simulation
    solver = SolverSettings(s.method, s.rtol, s.atol, min_step=s.min_step, max_steps=s.max_steps)
    y0 = model.initial_state(case.initial.lateral_perturbation, case.initial.seed)
    state = RunState.start(model, y0)
    times = sample_step * np.arange(1, int(round(t_end / sample_step)) + 1)
    rows, top = [], []
    for t in times:
        run = advance(model, solver, state, float(t), output_times=[float(t)])
        if not run.success:
            raise RuntimeError(f"the synthetic record's run stopped at {run.state.t:g} s: {run.message}")
        state = run.state
        rows.append(run.outputs[-1])
        top.append(float(model.top_u @ state.y[:n]))
    rows = np.array(rows)
    observed = {name: rows[:, OBSERVABLE_COLUMN[name]] for name in
                ("quill_speed", "surface_torque") + DOWNHOLE}
    hook = np.full(len(times), model.static.weight_on_hook)
    if getattr(model.hook_load, "adds", False):
        from drillstring.forces.registry import HookContext

        hook = hook - model.hook_load.evaluate_at(HookContext(times, model.static.weight_on_bit))
    return times, observed, np.array(top), hook, model


def _index(time: np.ndarray, t: float) -> int:
    return int(np.argmin(np.abs(time - t)))


def make_synthetic_record(case="stick_slip", seed: int = SEED, *, duration: float = 80.0, transient: float = 30.0,
                          sample_step: float = 0.1, dispersion: float = DISPERSION) -> SyntheticRecord:
    """The synthetic record of ``case`` (a :class:`~drillstring.case.Case` or a built-in case's name) seeded
    ``seed`` (module docstring): ``duration`` [s] sampled every ``sample_step`` [s] after ``transient`` [s]."""
    from drillstring.forces.bit_rock import case_bit_rock

    if not hasattr(case, "operation"):
        from drillstring.case import load_case

        case = load_case(case)
    for name, value, low in (("duration", duration, sample_step), ("transient", transient, 0.0),
                             ("sample_step", sample_step, 0.0)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > low):
            raise ValueError(f"{name} = {value!r}: must be a number of seconds above {low:g}")
    times, observed, top, hook, model = _sample_run(case, seed, transient + duration, sample_step, dispersion)
    keep = times >= transient - 1e-9 * sample_step
    time = np.round(times[keep] - times[keep][0], 9)
    truth = {
        "top_speed": observed["quill_speed"][keep],
        "surface_torque": observed["surface_torque"][keep],
        "hook_load": hook[keep],
        "block_position": BLOCK_START - top[keep],
    }
    truth.update({name: observed[name][keep] for name in DOWNHOLE})
    streams = np.random.SeedSequence(int(seed)).spawn(1 + len(NOISE))[1:]
    measured = {}
    for (name, sigma), stream in zip(NOISE.items(), streams):
        noise = np.random.default_rng(stream).standard_normal(len(time))
        measured[name] = truth[name] + sigma * noise + (HOOK_LOAD_BIAS if name == "hook_load" else 0.0)
    n = len(time)
    present = np.ones(n, dtype=bool)
    faults = {name: np.zeros(n, dtype=np.int8) for name in NOISE}
    null = {name: np.zeros(n, dtype=bool) for name in NOISE}
    for kind, channel, first, last, detail in FAULTS:
        if first > time[-1]:
            continue
        a, b = _index(time, first), _index(time, last) + 1
        names = list(NOISE) if channel == "all" else [channel]
        for name in names:
            if kind in ("empty", "null", "gap"):
                measured[name][a:b] = np.nan
                faults[name][a:b] = MISSING
                if kind == "null":
                    null[name][a:b] = True
            elif kind == "spike":
                measured[name][a:b] += detail
                faults[name][a:b] = SPIKE
            elif kind == "frozen":
                measured[name][a:b] = measured[name][a]
                faults[name][a:b] = FROZEN
        if kind == "gap":
            present[a:b] = False
    law = case_bit_rock(case)
    parameters: dict[str, tuple[float | str, str, str]] = {
        "case": (case.name, "", "the case simulated"),
        "model": ("random-matrix realization of the case-2 reduced model", "",
                  "drillstring.stochastic.random_matrices, the case's top drive; not the estimator's model"),
        "dispersion": (dispersion, "", "dispersion of the random mass, stiffness and damping matrices"),
        "seed": (int(seed), "", "numpy.random.SeedSequence seed: model matrices, then each channel's noise"),
        "transient": (transient, "s", "simulated time dropped before the record starts"),
        "sample_step": (sample_step, "s", "sampling step"),
        "hook_load_bias": (HOOK_LOAD_BIAS, "N", "bias of the hook-load sensor (measured = true + bias + noise)"),
        "static_hook_load": (float(model.static.weight_on_hook), "N", "the model's hook load (weight less weight on bit)"),
        "block_start": (BLOCK_START, "m", "block height at the run's t = 0"),
    }
    for name, sigma in NOISE.items():
        parameters[f"noise_{name}"] = (sigma, _SI[name], f"standard deviation of the {name} sensor's noise")
    for name in ("a1", "a2", "a3", "a4", "a5", "e"):
        if hasattr(law, name):
            parameters[f"bit_rock_{name}"] = (float(getattr(law, name)), "", f"the case's bit-rock coefficient {name} (SI)")
    parameters["weight_on_bit"] = (float(case.operation.weight_on_bit), "N", "the case's static weight on bit")
    parameters["top_speed_set_point"] = (float(case.operation.top_speed), "rad/s", "the top drive's set point")
    return SyntheticRecord(time, measured, present, truth, faults, parameters, null)


def _cell(value: float, decimals: int) -> str:
    return "" if not math.isfinite(value) else f"{value:.{decimals}f}"


def record_text(record: SyntheticRecord, truth_name: str = "stick_slip_surface_truth.csv") -> str:
    """The record file's text: ``#`` lines, the header ``TIME [s],RPM [rpm],...``, a row per present sample."""
    from drillstring.estimation.faults import DIMENSION
    from drillstring.units import TIME, unit_factor

    scale = {name: 1.0 / unit_factor(unit, DIMENSION[name] if name != "time" else TIME)
             for name, unit in FILE_UNITS.items()}
    lines = [(f"# drillstring synthetic surface record of case {record.parameters['case'][0]}, seed "
              f"{record.parameters['seed'][0]}: made by drillstring.estimation.synthetic "
              "(benchmarks/make_surface_record.py)"),
             f"# its hidden truth: {truth_name}",
             ",".join(f"{column} [{unit}]" for column, unit in FILE_COLUMNS.values())]
    for k in np.nonzero(record.present)[0]:
        cells = [_cell(record.time[k] * scale["time"], DECIMALS["time"])]
        for name in NOISE:
            cells.append("-999.25" if record.null[name][k] else _cell(record.measured[name][k] * scale[name],
                                                                       DECIMALS[name]))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


def truth_text(record: SyntheticRecord) -> str:
    """The truth file's text: ``# name = value [unit]  what`` lines, then the truth columns in SI and the faults."""
    lines = ["# hidden truth of the synthetic surface record (drillstring.estimation.synthetic); SI units"]
    for name, (value, unit, what) in record.parameters.items():
        shown = repr(value) if isinstance(value, str) else f"{value!r}"
        lines.append(f"# {name} = {shown}{f' [{unit}]' if unit else ''}  ({what})")
    names = list(record.truth)
    lines.append(",".join(["time [s]"] + [f"{n} [{_SI[n]}]" for n in names] + [f"fault_{n}" for n in NOISE]))
    for k in range(len(record.time)):
        cells = [f"{record.time[k]:.2f}"] + [f"{record.truth[n][k]:.9g}" for n in names]
        cells += [str(int(record.faults[n][k])) for n in NOISE]
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


def write_synthetic_record(record: SyntheticRecord, record_path: str | Path, truth_path: str | Path) -> None:
    """Write the record and its truth (atomically)."""
    from drillstring.files import write_text_atomic

    write_text_atomic(record_path, record_text(record, Path(truth_path).name))
    write_text_atomic(truth_path, truth_text(record))


def read_truth(path: str | Path) -> tuple[dict[str, str], dict[str, np.ndarray]]:
    """The truth file of :func:`truth_text`: ``(parameters, columns)``: the parameters as text (name -> the text
    after ``=``), the columns by name (without units) as arrays."""
    from drillstring.files import read_input_text

    text = read_input_text(path, what="truth file", max_bytes=20 * 1024 * 1024)
    parameters, rows = {}, []
    for line in text.splitlines():
        if line.startswith("#"):
            key, sep, rest = line[1:].partition("=")
            if sep:
                parameters[key.strip()] = rest.strip()
        elif line.strip():
            rows.append(line.split(","))
    names = [cell.partition("[")[0].strip() for cell in rows[0]]
    data = np.array([[float(c) for c in row] for row in rows[1:]])
    return parameters, {name: data[:, j] for j, name in enumerate(names)}
