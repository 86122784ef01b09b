"""Regenerate the shipped synthetic surface record and its hidden truth (drillstring.estimation.synthetic):
src/drillstring/cases/stick_slip_surface.csv and stick_slip_surface_truth.csv, seeded, reproducibly.

    python benchmarks/make_surface_record.py            # write both files
    python benchmarks/make_surface_record.py --check    # regenerate and compare with the shipped files

Prints the generation time (the simulation, sampled at every record step, and the noise), the files' sizes
and, with --check, whether they are equal to the shipped ones (data rows compared number by number: equal,
or within one unit of the last decimal written, which a different floating-point library may flip).
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


def _rows(text: str) -> list[list[str]]:
    return [line.split(",") for line in text.splitlines() if line and not line.startswith("#")]


def same_numbers(a: str, b: str) -> tuple[bool, str]:
    """Whether two CSV texts hold the same header and numbers (each within one unit of its last decimal)."""
    ra, rb = _rows(a), _rows(b)
    if len(ra) != len(rb) or ra[:1] != rb[:1]:
        return False, f"{len(ra)} rows vs {len(rb)}, or another header"
    for k, (x, y) in enumerate(zip(ra[1:], rb[1:]), start=1):
        for cx, cy in zip(x, y):
            if cx == cy:
                continue
            try:
                fx, fy = float(cx), float(cy)
            except ValueError:
                return False, f"row {k}: {cx!r} vs {cy!r}"
            decimals = len(cx.partition(".")[2]) if "e" not in cx.lower() else 9
            if abs(fx - fy) > 1.01 * 10.0 ** -decimals * max(1.0, abs(fx) if "e" in cx.lower() else 1.0):
                return False, f"row {k}: {cx} vs {cy}"
    return True, "equal"


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
