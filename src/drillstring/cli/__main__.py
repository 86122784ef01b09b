"""``python -m drillstring.cli``: the console script."""

from drillstring.cli import run

run()
