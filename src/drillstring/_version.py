"""The package's version, read from its installed metadata (``pyproject.toml``'s ``version``), so that it
is written in one place; modules that record it (stores, NetCDF files, reports, ``--version``) import it
from here, not from the package's ``__init__``."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("drillstring")
except PackageNotFoundError:  # a source tree on sys.path that was never installed
    __version__ = "0+unknown"
