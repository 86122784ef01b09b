"""Build the documentation site into ``docs/_build/html``: ``python docs/build.py`` from any folder, with the
package installed with its ``docs`` extra (``pip install -e ".[docs]"``).

Sphinx runs with warnings as errors (``-W --keep-going``), so the build fails on a broken internal link (a
page, a heading anchor or a file that does not exist), a docstring or page that does not parse, a page left out
of the table of contents, or a tutorial notebook whose cell raises (the notebooks are executed at every build;
``--no-execute`` skips them for a quick look at the text). Other arguments go to ``sphinx-build``.
``tests/test_docs.py`` builds small sites through :func:`build` to show that each of these fails.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parent


def build(source: Path = DOCS, output: Path | None = None, *, execute: bool = True, extra: list[str] = (),
          capture: bool = False) -> subprocess.CompletedProcess:
    """Run ``sphinx-build -W --keep-going -b html source output`` (default output ``source/_build/html``)
    in a fresh process; ``execute=False`` leaves the notebooks unexecuted."""
    env = {**os.environ, "DRILLSTRING_DOCS_EXECUTE": "force" if execute else "off"}
    output = Path(source) / "_build" / "html" if output is None else output
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", str(source), str(output),
               *extra]
    return subprocess.run(command, env=env, capture_output=capture, text=True)


def main(argv: list[str]) -> int:
    args = list(argv)
    execute = "--no-execute" not in args
    args = [a for a in args if a != "--no-execute"]
    start = time.perf_counter()
    done = build(execute=execute, extra=args)
    print(f"docs: sphinx-build exited {done.returncode} in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return done.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
