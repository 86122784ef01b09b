"""The kernel cache's fault of issue 33, end to end: a law module added to the package that does not import
Numba must not let a cached dispatch run another law.

For a source tree: copy its package to a temporary folder, run a Detournay case (a cold compile into an empty
Numba cache), add ``forces/aardvark.py`` (a bit law named to sort first, its kernel imported from the off-bottom
module: the new file imports no Numba), run the same case again with the same cache. Prints the mean force on
bit of both runs [kN] and whether the cache was reused; the two must agree. On b1c1e75 the second run reused the
cached kernels (the cache folder was keyed on the files importing Numba only) while the codes had shifted (ranks
among sorted names): the cached dispatch ran the off-bottom law for the Detournay case, 0 kN on bit. Run:

    .venv/bin/python benchmarks/cache_fault.py /path/to/tree [/path/to/other/tree ...]
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

AARDVARK = '''"""A bit law added to the package whose module imports no Numba (its kernel is the off-bottom one)."""
from dataclasses import dataclass
from typing import ClassVar

from drillstring.forces.off_bottom import OffBottom, off_bottom_kernel
from drillstring.forces.registry import register


@register
@dataclass(frozen=True)
class Aardvark(OffBottom):
    name: ClassVar[str] = "aardvark"
    kernel: ClassVar = off_bottom_kernel
'''

RUN = '''
import json, os, time
from pathlib import Path
from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
case = load_case("stick_slip")
case = case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"law": "detournay"}),
                               "initial": case.initial.model_copy(update={"start": "on_bottom"})})
model = case_reduced_model(case)
start = time.process_time()
result = simulate_model(model, t_end=0.5, output_step=0.05, lateral_perturbation=0.0)
cpu = time.process_time() - start
folders = sorted(p.name for p in Path(os.environ["NUMBA_CACHE_DIR"]).parent.glob("kernels-*"))
print(json.dumps({"force_on_bit_kN": float(result.observables["force_on_bit"].mean()) / 1e3, "cpu_s": cpu,
                  "cache_folders": folders}))
'''


def _run(package_parent: Path, cache: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(package_parent), NUMBA_CACHE_DIR=str(cache), OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    done = subprocess.run([sys.executable, "-c", RUN], env=env, capture_output=True, text=True)
    if done.returncode:
        return {"error": done.stderr.strip().splitlines()[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def check(tree: Path) -> dict:
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        shutil.copytree(tree / "src" / "drillstring", work / "pkg" / "drillstring",
                        ignore=shutil.ignore_patterns("__pycache__"))
        before = _run(work / "pkg", work / "cache")
        (work / "pkg" / "drillstring" / "forces" / "aardvark.py").write_text(AARDVARK)
        after = _run(work / "pkg", work / "cache")
    return {"tree": str(tree), "before": before, "after": after}


def main() -> None:
    for tree in sys.argv[1:]:
        print(json.dumps(check(Path(tree).resolve())), flush=True)


if __name__ == "__main__":
    main()
