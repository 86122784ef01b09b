"""What every figure of the package shares (no physics here): a Matplotlib figure on the Agg canvas, without
``pyplot`` (nothing changes the global backend or leaves figures open: safe in scripts, notebooks, worker
processes and tests), its atomic PNG file, the axes' titles and display units (:mod:`drillstring.units`,
unit system ``units``: ``"si"``, ``"field"``, or None: ``$DRILLSTRING_UNITS``, else si), the probes of a
run and a case's name as plain text."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from drillstring.files import atomic_output
from drillstring.quantities import DISPLAY_KINDS
from drillstring.units import DisplayUnit, display_unit

#: rpm per rad/s.
RPM = 60.0 / (2.0 * math.pi)

#: name -> short title for the axes (units: drillstring.quantities.DISPLAY_KINDS in the chosen system).
TITLES: dict[str, str] = {
    "rate_of_penetration": "rate of penetration",
    "bit_speed": "bit speed",
    "torque_on_bit": "torque-on-bit",
    "force_on_bit": "force-on-bit",
    "radial_displacement": "radial displacement",
    "contact_force": "contact force",
    "quill_speed": "quill speed",
    "surface_torque": "surface torque",
    "depth_of_cut": "depth of cut",
    "hook_load": "hook load",
    "wear_flat_force": "wear-flat force",
    "motor_speed": "motor speed",
    "motor_torque": "motor torque",
    "differential_pressure": "differential pressure",
}

_DPI = 120
#: Colours of a study's mean, nominal run and envelope.
MEAN_COLOR = "C0"
NOMINAL_COLOR = "C3"
ENVELOPE_COLOR = "C0"


def new_figure(rows: int, cols: int, size: tuple[float, float], sharex: bool = False, *,
               margins: dict[str, float] | None = None) -> tuple[Figure, np.ndarray]:
    """A figure of ``rows`` × ``cols`` axes (returned flat) on the Agg canvas: constrained layout, or the fixed
    ``margins`` (``Figure.subplots_adjust``'s keywords)."""
    fig = Figure(figsize=size, layout=None if margins else "constrained")
    FigureCanvasAgg(fig)
    axes = np.asarray(fig.subplots(rows, cols, squeeze=False, sharex=sharex)).ravel()
    if margins:
        fig.subplots_adjust(**margins)
    return fig, axes


def save_png(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` as PNG, atomically (a reader never sees a partial file)."""
    path = Path(path)
    with atomic_output(path) as temporary:
        fig.savefig(temporary, dpi=_DPI, format="png")
    return path


def panel_grid(n: int) -> tuple[int, int]:
    """(rows, columns) of a figure of ``n`` small panels: at most 4 columns, 2 up to 4 panels."""
    cols = min(n, 4) if n > 4 else min(n, 2) if n > 1 else 1
    return math.ceil(n / cols), cols


def axis_label(name: str, units: str | None) -> str:
    return f"{TITLES[name]} [{display_unit(DISPLAY_KINDS[name], units).label}]"


def axis_unit(kind: str | None, units: str | None = None) -> DisplayUnit:
    """The display unit of a plotted quantity of display kind ``kind`` (:func:`drillstring.units.display_unit`)
    in the unit system ``units``; None: a plain number (``"-"``)."""
    return DisplayUnit("-", 1.0) if kind is None else display_unit(kind, units)


def scaled(values, name: str, units: str | None) -> np.ndarray:
    return np.asarray(values, dtype=float) * display_unit(DISPLAY_KINDS[name], units).scale


def probe_index(x: np.ndarray, probe_x: float) -> int:
    if x.size == 0:
        raise ValueError("the dataset has no probe")
    return int(np.argmin(np.abs(x - probe_x)))


def probe_positions(ds: xr.Dataset) -> np.ndarray:
    if "x" in ds.coords or "x" in ds:
        return np.atleast_1d(np.asarray(ds["x"].values, dtype=float))
    n = ds.sizes.get("probe", 0)
    return np.full(n, np.nan)


def case_name(case_toml: str) -> str:
    """The ``name = "..."`` of a case's TOML text ('' when absent), as plain text for a figure: its dollar
    signs escaped, so that Matplotlib never reads it as mathtext."""
    try:
        name = tomllib.loads(str(case_toml)).get("name", "")
    except (tomllib.TOMLDecodeError, RecursionError):
        name = _case_name_line(case_toml)
    return str(name).replace("$", r"\$")


def _case_name_line(case_toml: str) -> str:
    """The ``name = "..."`` line of a TOML text that does not parse ('' when absent)."""
    for line in str(case_toml).splitlines():
        stripped = line.strip()
        if stripped.startswith("name") and "=" in stripped:
            key, value = stripped.split("=", 1)
            if key.strip() == "name":
                return value.strip().strip('"').strip("'")
        if stripped.startswith("["):
            break
    return ""


