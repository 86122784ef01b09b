"""Build the documentation site into ``docs/_build/html``: ``python docs/build.py`` from any folder, with the
package installed with its ``docs`` extra (``pip install -e ".[docs]"``).

Sphinx runs with warnings as errors (``-W --keep-going``), so the build fails on a broken internal link (a
page, a heading anchor or a file that does not exist), a docstring or page that does not parse, a page left out
of the table of contents, or a tutorial notebook whose cell raises (the notebooks are executed at every build;
``--no-execute`` skips them for a quick look at the text). Extra arguments go to ``sphinx-build``.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    args = list(argv)
    env = None
    if "--no-execute" in args:
        args.remove("--no-execute")
        import os

        env = {**os.environ, "DRILLSTRING_DOCS_EXECUTE": "off"}
    start = time.perf_counter()
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", str(DOCS),
               str(DOCS / "_build" / "html"), *args]
    done = subprocess.run(command, env=env)
    print(f"docs: sphinx-build exited {done.returncode} in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return done.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
