"""Coverage of the estimator's 90 % bands of bit speed and torque on bit against the truth, on the record shipped
with the stick_slip case and on the stick-slip twin of tests/estimation/twin.py, for settings given on the
command line (docs/estimation.md, "Coverage and relaxation").

    python benchmarks/estimator_coverage.py [--shipped SECONDS] [--twin SECONDS] [--members N] [--seeds 0,1]
        [--twin-truths 1] [--twin-dispersion 0.05] [--own-truths 1,2,3]
        [--config "relaxation=0.5 parameter_relaxation=0.5"] [--config "model_dispersion=0.05"] ...

Each ``--config`` (a space-separated list of EstimatorSettings fields over the case's defaults; "" the defaults)
runs on both records for each seed (the estimator's seed; the twin's truth is seed 1's, as the tests'). The
shipped record is read at 10 Hz as shipped, its first ``--shipped`` seconds, coverage over the whole record (the
spin-up runs before it); the twin's coverage is counted after its first 10 s (its filter starts from the model's
initial state). One line per run: coverage of bit speed and torque on bit, the torque on bit's while the truth
sticks (bit speed below STICK rad/s) and while it slips, the bit speed's RMSE, the members replaced, the wall
time, the number of independent samples the truth-in-band series is worth for each channel
(:func:`effective_samples`) with the standard deviation ``sqrt(0.9 · 0.1 / n)`` that a run's coverage would have
over records if the band were exactly calibrated, with ``particle_share`` > 0 the particle weights' effective
sample size over the analyses (median and smallest) and the estimated parameters' 5/50/95 % quantiles at the
record's end (the bit-rock coefficient, and the friction factor and the torsional stiffness's factor where
estimated; the weight-on-bit bias aside). Before the runs it prints each twin truth's lowest elastic torsional
angular frequency and the estimator's model's (docs/estimation.md "The torsional stiffness").
``model_dispersion`` (each member its own random reduced model, docs/estimation.md "Model uncertainty in the
members") is one of the settings a ``--config`` may set. ``--twin-truths`` runs one twin per truth seed (another
draw of the truth's random matrices and of its sensor noise; records ``twin<seed>``), ``--twin-dispersion`` sets the
truth's dispersion (0: the case's full basis on its nominal matrices; with an estimator of ``axial_modes=10
torsional_modes=10`` nearly the estimator's own model). The last lines pool each configuration's runs per record
kind (the mean coverage over the seeds and truths, its smallest and largest, and how many runs have both channels in
85-95 %): one record is one draw of the model's error, and the bands' calibration is a statement over draws
(docs/estimation.md, "Long records: the kicks and the coefficient"); then, per channel, each record's mean coverage
over the seeds and the spread of those means between the records against the seeds' own
(:func:`spread_between_records`; docs/estimation.md, "Calibration on each record"). ``--own-truths`` adds
perfect-model twins (records ``own<seed>``, kind "own"): the truth one member of each configuration's own prior
model, drawn afresh for each configuration (tests/estimation/twin.py ``own_model_twin``), as long as ``--twin``,
coverage after its first 10 s (``--own-model``: draw them from these settings instead, the same truths for every
configuration, to try a filter's setting on a fixed truth); there the bands' misses are the filter's own
(docs/estimation.md, "The filter's own share").
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from drillstring.api.estimates import builtin_record
from drillstring.case import load_case
from drillstring.estimation.ensemble import (
    EstimatorSettings,
    case_estimator_settings,
    estimate,
    estimator_model,
)
from drillstring.estimation.reading import read_surface_record
from drillstring.estimation.surface import SurfaceRecord
from drillstring.estimation.synthetic import read_truth

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "estimation"))
from twin import lowest_torsional_frequency, own_model_twin, twin

TWIN_START = 10.0  # [s] the twin's coverage is counted from here
STICK = 1.0  # [rad/s] the truth sticks below this bit speed


def effective_samples(inside: np.ndarray) -> float:
    """The number of independent samples that the series ``inside`` (the truth in the band, 0/1 at each time)
    is worth for its mean: ``n / τ``, ``τ = 1 + 2 Σ_k ρ_k`` its integrated autocorrelation time, the sum over
    lags up to the first window ``M ≥ 5 τ(M)`` (Sokal's automatic window). ``n`` where the series is constant."""
    x = np.asarray(inside, dtype=float)
    n = len(x)
    x = x - x.mean()
    variance = float(x @ x) / n
    if n < 2 or variance == 0.0:
        return float(n)
    tau = 1.0
    for lag in range(1, n):
        tau += 2.0 * float(x[:-lag] @ x[lag:]) / ((n - lag) * variance)
        if lag >= 5.0 * tau:
            break
    return n / max(tau, 1.0)


def spread_between_records(runs: list[tuple[str, float]]) -> tuple[dict, float, float]:
    """``(means, between, within)`` of one channel's coverage over ``runs`` (pairs of a record's name and one run's
    coverage, several seeds per record): each record's mean over its runs, the standard deviation of those means
    between the records and the seeds' own, the square root of the records' mean variance over their runs (both
    with ``ddof = 1``; nan where a record, or every record, has too few runs)."""
    by_record: dict[str, list[float]] = {}
    for name, value in runs:
        by_record.setdefault(name, []).append(float(value))
    means = {name: float(np.mean(values)) for name, values in by_record.items()}
    between = float(np.std(list(means.values()), ddof=1)) if len(means) > 1 else float("nan")
    variances = [np.var(values, ddof=1) for values in by_record.values() if len(values) > 1]
    within = float(np.sqrt(np.mean(variances))) if variances else float("nan")
    return means, between, within


def _settings(text: str) -> dict:
    fields = {f: type(getattr(EstimatorSettings(), f)) for f in EstimatorSettings.__dataclass_fields__}
    out = {}
    for item in text.split():
        key, value = item.split("=")
        out[key] = fields[key](value)
    return out


def _shipped(seconds: float):
    case = load_case("stick_slip")
    record_path, truth_path = builtin_record("stick_slip")
    record = read_surface_record(record_path, case=case)
    keep = record.time <= seconds + 1e-9
    record = SurfaceRecord(record.time[keep], {k: v[keep] for k, v in record.channels.items()},
                           {k: v[keep] for k, v in record.flags.items()}, "shipped")
    _, truth = read_truth(truth_path)
    return case, record, {name: np.interp(record.time, truth["time"], truth[name])
                          for name in ("bit_speed", "torque_on_bit")}, -np.inf


def _twin(seconds: float, truth_seed: int = 1, dispersion: float = 0.05):
    case = load_case("stick_slip")
    experiment = twin(case, seconds, seed=truth_seed, dispersion=dispersion)
    print(f"twin truth {truth_seed}: lowest torsional frequency {lowest_torsional_frequency(experiment.model):.4f} "
          "rad/s", flush=True)
    return case, experiment.record, experiment.truth, TWIN_START


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shipped", type=float, default=40.0)
    parser.add_argument("--twin", type=float, default=60.0)
    parser.add_argument("--members", type=int, default=16)
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--config", action="append", default=None)
    parser.add_argument("--twin-truths", default="1",
                        help="the twin truths' seeds (its random matrices and sensor noise; the tests' is 1)")
    parser.add_argument("--twin-dispersion", type=float, default=0.05,
                        help="the twin truth's random-matrix dispersion (0: the case's full basis, nominal matrices)")
    parser.add_argument("--own-truths", default="",
                        help="seeds of own-model twins: truths drawn from each configuration's own estimator model "
                             "(tests/estimation/twin.py own_model_twin), as long as --twin")
    parser.add_argument("--own-model", default=None,
                        help="the settings the own-model truths are drawn from, as a --config (default: each "
                             "configuration's own; \"\" the defaults: one truth for every configuration)")
    options = parser.parse_args()
    configs = options.config or [""]
    records = {}  # name: (kind, (case, record, truth, start)); the runs are pooled by kind
    if options.shipped > 0:
        records["shipped"] = ("shipped", _shipped(options.shipped))
    if options.twin > 0:
        truths = [int(t) for t in options.twin_truths.split(",") if t]
        for truth_seed in truths:
            records["twin" if truths == [1] else f"twin{truth_seed}"] = (
                "twin", _twin(options.twin, truth_seed, options.twin_dispersion))
    for truth_seed in (int(t) for t in options.own_truths.split(",") if t):
        records[f"own{truth_seed}"] = ("own", truth_seed)
    models = {}
    pooled: dict[tuple[str, str], list[tuple[float, float]]] = {}  # per configuration and record kind
    for config in configs:
        for name, (kind, experiment) in records.items():
            if kind == "own":  # the truth drawn from this configuration's own model
                case = load_case("stick_slip")
                truth_config = config if options.own_model is None else options.own_model
                own = own_model_twin(case, case_estimator_settings(case, spin_up=0.0, **_settings(truth_config)),
                                     options.twin, seed=experiment)
                experiment = (case, own.record, own.truth, TWIN_START)
                print(f"{name}: the truth's coefficient at the end {own.coefficient:.0f}, bias {own.bias:.0f} N")
            case, record, truth, start = experiment
            for seed in (int(s) for s in options.seeds.split(",")):
                start_now = {"spin_up": 0.0} if kind in ("twin", "own") else {}
                settings = case_estimator_settings(case, ensemble_size=options.members, seed=seed, **start_now,
                                                   **_settings(config))
                key = (settings.axial_modes, settings.torsional_modes)
                if key not in models:
                    models[key] = estimator_model(case, settings)
                    print("the estimator's model: lowest torsional frequency "
                          f"{lowest_torsional_frequency(models[key]):.4f} rad/s", flush=True)
                begin = time.perf_counter()
                result = estimate(case, record, settings, model=models[key])
                wall = time.perf_counter() - begin
                keep = result.time >= start
                rmse = float(np.sqrt(np.mean((result.mean["bit_speed"] - truth["bit_speed"])[keep] ** 2)))
                low, high = result.band("torque_on_bit")
                inside = (truth["torque_on_bit"] >= low) & (truth["torque_on_bit"] <= high)
                stick = np.abs(truth["bit_speed"]) < STICK
                phases = " ".join(f"{label} {np.mean(inside[keep & mask]):.2f} ({np.sum(keep & mask)})"
                                  if np.any(keep & mask) else f"{label} -"
                                  for label, mask in (("stick", stick), ("slip", ~stick)))
                coverage = (result.coverage("bit_speed", truth["bit_speed"], start),
                            result.coverage("torque_on_bit", truth["torque_on_bit"], start))
                speed_low, speed_high = result.band("bit_speed")
                speed_inside = (truth["bit_speed"] >= speed_low) & (truth["bit_speed"] <= speed_high)
                independent = [effective_samples(series[keep]) for series in (speed_inside, inside)]
                pooled.setdefault((config or "defaults", kind), []).append((name, coverage))
                print(f"{config or 'defaults':45s} {name:7s} seed {seed} N {options.members:3d} "
                      f"bit_speed {coverage[0]:.2f} torque_on_bit {coverage[1]:.2f} "
                      f"[{phases}] "
                      f"rmse {rmse:.2f} rad/s replaced {result.replaced_members} wall {wall:.0f} s "
                      f"independent samples {independent[0]:.0f} / {independent[1]:.0f} (a calibrated band's "
                      f"coverage ±{np.sqrt(0.09 / independent[0]):.3f} / ±{np.sqrt(0.09 / independent[1]):.3f})"
                      + ("" if result.effective_size is None else
                         " effective size median {:.0f} min {:.0f}".format(*np.nanquantile(result.effective_size,
                                                                                           [0.5, 0.0])))
                      + "".join(f" {p} end {'/'.join(f'{v:.4g}' for v in result.quantiles[p][-1])}"
                                for p in result.parameters if p != "weight_on_bit_bias"), flush=True)
    print("pooled over the seeds: mean coverage (smallest, largest), runs with both channels in 85-95 %")
    for (config, name), runs in pooled.items():
        values = np.array([coverage for _, coverage in runs])
        inside = int(np.sum(np.all((values >= 0.85) & (values <= 0.95), axis=1)))
        print(f"{config:45s} {name:7s} " + " ".join(
            f"{label} {values[:, j].mean():.3f} ({values[:, j].min():.2f}, {values[:, j].max():.2f})"
            for j, label in enumerate(("bit_speed", "torque_on_bit"))) + f" in range {inside} of {len(runs)}")
    print("per record, the mean over the seeds; the standard deviation of those means between the records and the "
          "seeds' own (docs/estimation.md, \"Calibration on each record\")")
    for (config, name), runs in pooled.items():
        for j, label in enumerate(("bit_speed", "torque_on_bit")):
            means, between, within = spread_between_records([(record, coverage[j]) for record, coverage in runs])
            print(f"{config:45s} {name:7s} {label:13s} "
                  + " ".join(f"{record} {mean:.3f}" for record, mean in means.items())
                  + f" between records {between:.3f} between seeds {within:.3f}")


if __name__ == "__main__":
    main()
