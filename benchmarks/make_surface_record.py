"""Regenerate the shipped synthetic surface record and its hidden truth (drillstring.estimation.synthetic):
src/drillstring/cases/stick_slip_surface.csv and stick_slip_surface_truth.csv, seeded, reproducibly.

    python benchmarks/make_surface_record.py            # write both files
    python benchmarks/make_surface_record.py --check    # regenerate and compare with the shipped files

Prints the generation time (the simulation, sampled at every record step, and the noise), the files' sizes
and, with --check, whether they are equal to the shipped ones (data rows compared number by number: equal, within
one unit of the last decimal written, or within TOLERANCE of the column's largest value, which another processor's
arithmetic reaches over the stick-slip run; the largest differences are printed).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from drillstring.estimation.synthetic import make_synthetic_record, record_text, truth_text

CASES = Path(__file__).resolve().parents[1] / "src" / "drillstring" / "cases"
RECORD = CASES / "stick_slip_surface.csv"
TRUTH = CASES / "stick_slip_surface_truth.csv"
#: [-] of a column's largest value: the truth is a stick-slip run, where the last bits of the model build and the
#: compiled loop (LAPACK's and Numba's code differ between processors) grow: on an AMD EPYC (AVX-512) the files
#: regenerate within 5.6e-4 (the torque on bit at the record's end) of the machine's that made them.
TOLERANCE = 1e-3


def _rows(text: str) -> list[list[str]]:
    return [line.split(",") for line in text.splitlines() if line and not line.startswith("#")]


def same_numbers(a: str, b: str, tolerance: float = TOLERANCE) -> tuple[bool, str]:
    """Whether two CSV texts hold the same header, the same empty cells and numbers within ``tolerance`` of
    their column's largest magnitude (or one unit of the last decimal written, where that is more); the reason
    (the largest relative difference of each column that has one)."""
    ra, rb = _rows(a), _rows(b)
    if len(ra) != len(rb) or ra[:1] != rb[:1]:
        return False, f"{len(ra)} rows vs {len(rb)}, or another header"
    header, worst = ra[0], {}
    columns = list(zip(*ra[1:])), list(zip(*rb[1:]))
    for name, xs, ys in zip(header, *columns):
        filled = [(cx, cy) for cx, cy in zip(xs, ys) if cx != cy]
        if not filled:
            continue
        try:
            scale = max(abs(float(c)) for c in xs if c)
            pairs = [(float(cx), float(cy), cx) for cx, cy in filled]
        except ValueError:
            return False, f"{name}: {filled[0][0]!r} vs {filled[0][1]!r}"
        for fx, fy, cx in pairs:
            decimals = len(cx.partition(".")[2]) if "e" not in cx.lower() else 9
            allowed = max(tolerance * scale, 1.01 * 10.0 ** -decimals * (abs(fx) if "e" in cx.lower() else 1.0))
            if abs(fx - fy) > allowed:
                return False, f"{name}: {cx} vs {fy!r}, {abs(fx - fy) / scale:.1e} of the column's largest value"
        worst[name] = max(abs(fx - fy) for fx, fy, _ in pairs) / scale
    if not worst:
        return True, "equal"
    return True, "equal within the tolerance; largest difference / column's largest value: " + ", ".join(
        f"{name} {value:.1e}" for name, value in worst.items())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the shipped files, write nothing")
    args = parser.parse_args()
    start = time.perf_counter()
    record = make_synthetic_record()
    elapsed = time.perf_counter() - start
    texts = {RECORD: record_text(record, TRUTH.name), TRUTH: truth_text(record)}
    print(f"generated {len(record.time)} samples ({int(record.present.sum())} rows) in {elapsed:.1f} s "
          "(Numba compile included on a cold cache)")
    failed = False
    for path, text in texts.items():
        if args.check:
            equal, why = same_numbers(path.read_text(encoding="utf-8"), text)
            print(f"{path.name}: {why}")
            failed |= not equal
        else:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path} ({len(text.encode()):,} bytes)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
