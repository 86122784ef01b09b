"""Print a pip constraints file that pins every dependency of pyproject.toml to its lower bound.

``pip install -c <(python3 .ci/floors.py) -e ".[test]"`` then installs the oldest versions the project
claims to support, so a test run in that environment checks the floors (see .ci/run). Every runtime
dependency must have a ``>=`` lower bound; the script fails when one has none.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9_.\-]+)\s*(\[[^\]]*\])?\s*(.*)$")


def lower_bound(requirement: str) -> tuple[str, str | None]:
    """``("numpy", "2.0")`` for ``"numpy>=2.0"``; the version is None without a ``>=`` bound."""
    match = REQUIREMENT.match(requirement)
    if match is None:
        raise ValueError(f"cannot read the requirement {requirement!r}")
    name, specifiers = match.group(1), match.group(3)
    floors = re.findall(r">=\s*([0-9][^,;\s]*)", specifiers.split(";")[0])
    return name, floors[0] if floors else None


def main() -> int:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    requirements = list(project["dependencies"]) + list(project.get("optional-dependencies", {}).get("test", []))
    missing = []
    for requirement in requirements:
        name, floor = lower_bound(requirement)
        if floor is None:
            missing.append(name)
        else:
            print(f"{name}=={floor}")
    if missing:
        print(f"no lower bound for: {', '.join(missing)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
