"""Results as xarray Datasets: one name and one unit per quantity, NetCDF I/O.

Variable names are the same across code, files and figures: ``rate_of_penetration`` [m/s],
``bit_speed`` [rad/s], ``torque_on_bit`` [N·m], ``force_on_bit`` [N], ``bit_depth`` [m],
``nodes_in_contact`` [-], ``contact_force`` [N], ``radial_displacement`` [m] (dimension ``probe``,
coordinate ``x`` [m]) and ``lateral_displacement`` [m] (dimensions ``probe`` and ``direction`` = y, z: the
whirl orbit).
"""

from __future__ import annotations

import io

from pathlib import Path

import numpy as np
import xarray as xr

from drillstring._version import __version__
from drillstring.dynamics.simulate import SimulationResult
from drillstring.files import atomic_output
from drillstring.quantities import LONG_NAMES, UNITS

def run_dataset(result: SimulationResult, *, case_toml: str = "", extra_attrs: dict | None = None
                ) -> xr.Dataset:
    """The observables of one run as a Dataset with units, the case and the solver statistics."""
    data = {
        name: ("time", values, {"units": UNITS[name], "long_name": LONG_NAMES[name]})
        for name, values in result.observables.items()
    }
    data["radial_displacement"] = (
        ("time", "probe"), result.radial_displacement,
        {"units": "m", "long_name": LONG_NAMES["radial_displacement"]},
    )
    data["lateral_displacement"] = (
        ("time", "probe", "direction"), result.lateral_displacement,
        {"units": "m", "long_name": LONG_NAMES["lateral_displacement"]},
    )
    coords = {
        "time": ("time", result.time, {"units": "s"}),
        "direction": ("direction", np.array(["y", "z"])),
        "x": ("probe", result.probe_positions, {"units": "m", "long_name": "probe position from the top"}),
        "gap": ("probe", result.probe_gaps, {"units": "m", "long_name": "radial gap to the borehole"}),
    }
    attrs = {
        "drillstring_version": __version__,
        "case": case_toml,
        "status": result.status,
        "message": result.message,
        "impacts": int(result.impacts),
    }
    attrs.update({f"solver_{k}": v for k, v in result.stats.items() if isinstance(v, (int, float, str))})
    attrs.update(extra_attrs or {})
    return xr.Dataset(data, coords=coords, attrs=attrs)


def write_netcdf(dataset: xr.Dataset, path: str | Path) -> Path:
    """Write ``dataset`` to NetCDF-4 (h5netcdf engine), atomically (a complete file or the previous
    one, never a partial file); returns the path."""
    path = Path(path)
    clean = dataset.copy()
    clean.attrs = {k: (int(v) if isinstance(v, (bool, np.bool_)) else v) for k, v in dataset.attrs.items()}
    buffer = io.BytesIO()  # built in memory, then written by Python: a full disk is one clean OSError,
    clean.to_netcdf(buffer, engine="h5netcdf")  # never HDF5 errors printed while its objects are freed
    with atomic_output(path) as temporary:
        temporary.write_bytes(buffer.getvalue())
    return path


def read_netcdf(path: str | Path) -> xr.Dataset:
    """Read a Dataset written by :func:`write_netcdf` (loaded into memory, file closed)."""
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        return ds.load()
