"""Benchmark: the driver's CPU per realization written to a study's store (``TaskStore.write_many``).

A study's driver process writes each batch of outcomes to its Zarr store while the workers compute: on a
machine with as many workers as cores that CPU is taken from them. This times the writes of one reference
study's realizations (real store layout, outcomes with the shapes a realization returns, random values) in
batches of the store's ``flush_count``, for this tree's writer and for the previous recipe (each array opened
again per batch, a Zarr call per row of the one-chunk-per-row arrays, the small arrays read and rewritten
whole), the two alternating batch by batch in one run. Prints the milliseconds per realization of each and
their ratio, and checks that both stores hold the same data. Run:

    .venv/bin/python benchmarks/bench_store_writes.py [--samples 240] [--batch 8]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import zarr

from drillstring.case import load_case
from drillstring.stochastic import montecarlo as mc
from drillstring.stochastic.store import DONE


def previous_assign(store, writes: dict[str, list]) -> None:
    """The previous writer (for comparison only)."""
    with zarr.config.set({"array.write_empty_chunks": True}):
        for name, rows in writes.items():
            array = zarr.open_array(store.group.store, path=store.group[name].path, mode="r+")
            if array.ndim > 1 and array.chunks[0] == 1:
                for index, value in rows:
                    array[index] = value
            else:
                whole = array[...]
                for index, value in rows:
                    whole[index] = value
                array[...] = whole


def outcome(case, settings, index: int, rng: np.random.Generator) -> mc.RealizationOutcome:
    n_t = len(settings.time)
    observables = {name: rng.standard_normal(n_t) for name in mc.study_observables(case)}
    metrics = {name: float(rng.standard_normal()) for name in
               {**mc.REALIZATION_METRICS, **mc.FAMILY_GROWTH_METRICS}}
    return mc.RealizationOutcome(index, 1.06e6 + rng.standard_normal(), 1e5, DONE, "", observables,
                                 rng.standard_normal((n_t, len(case.mesh.probes))), 0.05, 1000,
                                 float(rng.standard_normal()), rng.standard_normal(1), metrics)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=240)
    parser.add_argument("--batch", type=int, default=None, help="realizations per write (default: the store's "
                        "flush_count)")
    args = parser.parse_args()
    case = load_case("reference")
    settings = mc.StudySettings(samples=args.samples, laws=(mc.weight_on_hook_normal(case, 5000.0),))
    rng = np.random.default_rng(0)
    batch = args.batch or mc.StudyStore.flush_count
    outcomes = [outcome(case, settings, i, rng) for i in range(args.samples)]
    folder = Path(tempfile.mkdtemp(prefix="bench_store_"))
    try:
        stores = {"this tree": mc.StudyStore(folder / "new.zarr", case, settings),
                  "previous": mc.StudyStore(folder / "old.zarr", case, settings)}
        stores["previous"]._assign = lambda writes, s=stores["previous"]: previous_assign(s, writes)
        seconds = dict.fromkeys(stores, 0.0)
        for first in range(0, args.samples, batch):
            for name, store in stores.items():
                start = time.process_time()
                store.write_many(outcomes[first:first + batch])
                seconds[name] += time.process_time() - start
        equal = all(np.array_equal(stores["this tree"].group[k][...], stores["previous"].group[k][...],
                                   equal_nan=True) for k in stores["previous"].group.array_keys())
        print(f"{args.samples} realizations in batches of {batch}, driver CPU per realization:")
        for name, total in seconds.items():
            print(f"  {name:10s} {1e3 * total / args.samples:7.2f} ms")
        print(f"  ratio previous / this tree: {seconds['previous'] / seconds['this tree']:.2f}x; "
              f"stores equal: {equal}")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
