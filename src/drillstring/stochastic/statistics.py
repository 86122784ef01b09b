"""Statistics over Monte Carlo realizations (docs/model.md §11).

NumPy core functions, plus xarray wrappers that keep coordinates and units.

* Mean-square convergence of the Monte Carlo estimate with the number of realizations ``n``
  (Soize, *Uncertainty Quantification*, Springer 2017, §6; Ritto, Soize & Sampaio, "Stochastic
  drill-string dynamics – random weight-on-hook")::

      conv(n) = (1/n) Σ_{j=1..n} ∫₀^{t_f} ||U_j(t)||² dt                                       (1)

  with ``U_j`` the observable vector of realization ``j`` and the integral evaluated by the trapezoid rule
  on the output times. ``conv(n)`` levelling off shows that ``n`` realizations suffice.
* Pointwise mean, standard deviation and the **envelope of probability level** ``P_c`` by the method of
  quantiles: the ``(1 − P_c)/2`` and ``(1 + P_c)/2`` quantiles (2.5 % and 97.5 % for ``P_c = 0.95``).
* **Dispersion** (coefficient of variation) ``δ = std / |mean|``, pointwise.
* Summaries over time after a transient: time-mean and maximum of ``δ`` per observable, and their ratios
  to the dispersion of a random input (the *amplification* of the input uncertainty).

Failed realizations (NaN) must be removed by the caller before any of these (e.g.
``ds.dropna("realization", how="any")``): the functions refuse NaN input rather than silently skew the
statistics.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Mapping
from typing import Any

import numpy as np
import xarray as xr

__all__ = [
    "mean_square_convergence",
    "quantile_envelope",
    "dispersion",
    "realization_statistics",
    "dispersion_summary",
    "record_start",
]

#: Default quantile definition: NumPy's ``"linear"`` (Hyndman & Fan 1996, definition 7).
DEFAULT_QUANTILE_METHOD = "linear"


def _refuse_nan(values: np.ndarray, what: str) -> None:
    if np.isnan(values).any():
        n_bad = int(np.isnan(values).reshape(values.shape[0], -1).any(axis=1).sum()) if values.ndim else 1
        raise ValueError(
            f"{what} contain NaN ({n_bad} realization(s) affected): remove failed realizations first, "
            "e.g. ds.dropna('realization', how='any')"
        )


# ---------------------------------------------------------------------------------------------------------
# NumPy core
# ---------------------------------------------------------------------------------------------------------


def mean_square_convergence(samples: np.ndarray, time: np.ndarray) -> np.ndarray:
    """``conv(n)`` of eq. (1) for ``n = 1..n_s``.

    Parameters
    ----------
    samples:
        Realizations of the observable, shape ``(n_s, n_t)`` (scalar ``U``) or ``(n_s, n_t, n_c)`` (``n_c``
        components of ``U``; their units should make ``||U||²`` meaningful, e.g. scaled or same-unit
        components). Must not contain NaN or inf.
    time:
        Output times [s], shape ``(n_t,)``, strictly increasing. The integral runs over
        ``[time[0], time[-1]]`` (``= [0, t_f]`` when the output starts at 0).

    Returns
    -------
    ndarray, shape ``(n_s,)``
        ``conv(n)`` in [unit of U]²·s; ``conv[n-1]`` uses the first ``n`` realizations, in the given order.
    """
    u = np.asarray(samples, dtype=float)
    t = np.asarray(time, dtype=float)
    if u.ndim not in (2, 3):
        raise ValueError(f"samples must have shape (n_s, n_t) or (n_s, n_t, n_c), got {u.shape}")
    if t.ndim != 1 or t.size != u.shape[1]:
        raise ValueError(f"time must have shape ({u.shape[1]},) to match samples {u.shape}, got {t.shape}")
    if u.shape[0] == 0:
        raise ValueError("samples contain no realization (n_s = 0)")
    if t.size < 2:
        raise ValueError(f"time needs at least 2 points for the time integral, got {t.size}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
        raise ValueError("time must be finite and strictly increasing")
    _refuse_nan(u, "samples")
    if not np.all(np.isfinite(u)):
        raise ValueError("samples contain inf: remove diverged realizations first")
    sq = u * u
    if sq.ndim == 3:
        sq = sq.sum(axis=2)  # ||U_j(t)||²
    energy = np.trapezoid(sq, t, axis=1)  # ∫ ||U_j||² dt per realization
    n = np.arange(1, u.shape[0] + 1, dtype=float)
    return np.cumsum(energy) / n


def _check_level(level: float) -> float:
    lv = float(level)
    if not (0.0 < lv < 1.0):
        raise ValueError(f"level = {level!r} must be a probability in (0, 1), e.g. 0.95")
    return lv


def quantile_envelope(
    samples: np.ndarray, level: float = 0.95, axis: int = 0, *, method: str = DEFAULT_QUANTILE_METHOD
) -> tuple[np.ndarray, np.ndarray]:
    """Envelope of probability ``level`` by the method of quantiles.

    Returns the ``(1 − level)/2`` and ``(1 + level)/2`` quantiles of ``samples`` along ``axis`` (the
    realizations), e.g. 2.5 % and 97.5 % for ``level = 0.95``; same units as ``samples``.

    Quantile definition: ``numpy.quantile(..., method=method)``; the default ``"linear"`` is Hyndman & Fan
    (1996) definition 7: with the sorted sample ``x_(0) ≤ … ≤ x_(n−1)``, the ``q`` quantile interpolates
    linearly at the fractional position ``(n − 1) q``. Any other NumPy method name (e.g. ``"inverted_cdf"``,
    ``"median_unbiased"``) may be passed. NaN input is refused.
    """
    x = np.asarray(samples, dtype=float)
    lv = _check_level(level)
    if x.ndim == 0 or x.shape[axis] == 0:
        raise ValueError("samples contain no realization along the realization axis")
    _refuse_nan(np.moveaxis(x, axis, 0), "samples")
    lower, upper = np.quantile(x, [0.5 * (1.0 - lv), 0.5 * (1.0 + lv)], axis=axis, method=method)
    return lower, upper


def dispersion(samples: np.ndarray, axis: int = 0, *, ddof: int = 1) -> np.ndarray:
    """Pointwise dispersion (coefficient of variation) ``δ = std / |mean|`` along ``axis`` (dimensionless).

    ``std`` is the sample standard deviation with ``ddof = 1`` by default (unbiased variance estimator,
    divisor ``n − 1``; needs at least 2 realizations). Where ``mean == 0`` exactly, ``δ`` is undefined and
    NaN is returned, without a floating-point warning. NaN input is refused.
    """
    x = np.asarray(samples, dtype=float)
    if x.ndim == 0:
        raise ValueError("samples must have at least one axis (the realizations)")
    n = x.shape[axis]
    if n <= ddof:
        raise ValueError(f"dispersion needs more than ddof = {ddof} realizations, got {n}")
    _refuse_nan(np.moveaxis(x, axis, 0), "samples")
    m = np.mean(x, axis=axis)
    s = np.std(x, axis=axis, ddof=ddof)
    am = np.abs(m)
    out = np.full(np.shape(m), np.nan)
    np.divide(s, am, out=out, where=am > 0.0)
    return out if np.ndim(out) else float(out)


# ---------------------------------------------------------------------------------------------------------
# xarray wrappers
# ---------------------------------------------------------------------------------------------------------


def _envelope_core(x: np.ndarray, level: float, method: str) -> tuple[np.ndarray, np.ndarray]:
    return quantile_envelope(x, level, axis=-1, method=method)


def realization_statistics(
    data: xr.DataArray | xr.Dataset,
    dim: Hashable = "realization",
    level: float = 0.95,
    *,
    method: str = DEFAULT_QUANTILE_METHOD,
    ddof: int = 1,
) -> xr.Dataset:
    """Statistics over the realizations of every variable of ``data`` that has dimension ``dim``.

    For each such variable ``v`` the result holds ``v_mean``, ``v_std`` (``ddof`` = 1 by default),
    ``v_lower`` and ``v_upper`` (the envelope of probability ``level``, see :func:`quantile_envelope`; quantile
    definition ``method``) and ``v_dispersion`` (``std/|mean|``, NaN where the mean is 0), each without ``dim``.
    The other dimensions and coordinates are kept (coordinates along ``dim`` are dropped), and the variable's
    attributes (``units``, ``long_name``, …) are copied; ``v_dispersion`` gets ``units = "1"``
    (dimensionless). Each output records its ``statistic``; the dataset records ``n_realizations``,
    ``level``, ``quantile_method`` and ``ddof``. Variables without ``dim`` are left out. A DataArray without a
    name is called ``"data"``. NaN input is refused (drop failed realizations first).
    """
    lv = _check_level(level)
    if isinstance(data, xr.DataArray):
        ds = data.to_dataset(name=data.name if data.name is not None else "data")
    elif isinstance(data, xr.Dataset):
        ds = data
    else:
        raise TypeError(f"data must be an xarray DataArray or Dataset, got {type(data).__name__}")
    if dim not in ds.dims:
        raise ValueError(f"dimension {dim!r} not found; dimensions are {list(ds.dims)}")
    n = int(ds.sizes[dim])
    if n <= ddof:
        raise ValueError(f"statistics need more than ddof = {ddof} realizations along {dim!r}, got {n}")
    names = [v for v in ds.data_vars if dim in ds[v].dims]
    if not names:
        raise ValueError(f"no data variable has the dimension {dim!r}")

    out: dict[str, xr.DataArray] = {}
    for v in names:
        da = ds[v]
        if bool(da.isnull().any()):
            n_bad = int(da.isnull().any([d for d in da.dims if d != dim]).sum()) if da.ndim > 1 else int(
                da.isnull().sum()
            )
            raise ValueError(
                f"variable {v!r} contains NaN in {n_bad} realization(s): remove failed realizations first, "
                f"e.g. ds.dropna({dim!r}, how='any')"
            )
        attrs = dict(da.attrs)
        long = attrs.get("long_name", str(v))
        mean_da = da.mean(dim, keep_attrs=True)
        std_da = da.std(dim, ddof=ddof, keep_attrs=True)
        lower, upper = xr.apply_ufunc(
            _envelope_core,
            da,
            kwargs={"level": lv, "method": method},
            input_core_dims=[[dim]],
            output_core_dims=[[], []],
            dask="parallelized",
            output_dtypes=[float, float],
            keep_attrs=True,
        )
        abs_mean = abs(mean_da)
        disp = xr.where(abs_mean > 0, std_da / abs_mean.where(abs_mean > 0), np.nan)
        q_lo, q_hi = 0.5 * (1.0 - lv), 0.5 * (1.0 + lv)
        stats_ = {
            "mean": (mean_da, {"statistic": "mean", "long_name": f"mean of {long}"}),
            "std": (std_da, {"statistic": "standard deviation", "ddof": ddof, "long_name": f"std of {long}"}),
            "lower": (
                lower,
                {"statistic": "quantile", "quantile": q_lo, "level": lv, "long_name": f"{q_lo:.2%} quantile of {long}"},
            ),
            "upper": (
                upper,
                {"statistic": "quantile", "quantile": q_hi, "level": lv, "long_name": f"{q_hi:.2%} quantile of {long}"},
            ),
            "dispersion": (
                disp,
                {
                    "statistic": "dispersion",
                    "definition": "std / |mean|",
                    "ddof": ddof,
                    "long_name": f"dispersion of {long}",
                },
            ),
        }
        for key, (arr, extra) in stats_.items():
            a = dict(attrs)
            a.update(extra)
            if key == "dispersion":
                a["units"] = "1"
            out[f"{v}_{key}"] = arr.rename(f"{v}_{key}").assign_attrs(a)

    result = xr.Dataset(out)
    result.attrs.update(
        {
            "n_realizations": n,
            "realization_dim": str(dim),
            "level": lv,
            "quantile_method": method,
            "ddof": ddof,
        }
    )
    return result


def _as_names(variables: str | Iterable[str]) -> list[str]:
    if isinstance(variables, str):
        return [variables]
    return [str(v) for v in variables]


def dispersion_summary(
    stats: xr.Dataset,
    variables: str | Iterable[str],
    *,
    t_transient: float,
    input_dispersion: Mapping[str, float] | None = None,
    time_dim: str = "time",
) -> dict[str, dict[str, Any]]:
    """Time summaries of the dispersion of each variable after the transient (plain, JSON-serialisable).

    For each name ``v`` in ``variables`` (reading ``stats[f"{v}_dispersion"]``, as written by
    :func:`realization_statistics`), over the output times ``t ≥ t_transient`` [s]:

    * ``dispersion_time_mean``: ``(1/(t_end − t_start)) ∫ δ(t) dt`` by the trapezoid rule on the retained
      times (the true time average, also for non-uniform output); with a single retained time, its value;
    * ``dispersion_max`` and ``time_of_max`` [s];
    * ``ratio_time_mean[name]`` and ``ratio_max[name]``: the above divided by each ``input_dispersion[name]``
      (e.g. ``{"weight_on_hook": δ_WOH, "weight_on_bit": δ_WOB}``) — how much the input dispersion is
      amplified;
    * ``t_start``, ``t_end``, ``n_times`` and ``n_undefined`` (times where ``δ`` is NaN because the mean is 0;
      they are left out of the mean and the maximum).

    Values are Python floats (``None`` when undefined). The dispersion must depend on ``time_dim`` only;
    select other dimensions first (e.g. ``stats.sel(node=...)``).
    """
    t0 = float(t_transient)
    if not math.isfinite(t0):
        raise ValueError(f"t_transient = {t_transient!r} must be finite")
    inputs: dict[str, float] = {}
    for key, val in (input_dispersion or {}).items():
        fv = float(val)
        if not (math.isfinite(fv) and fv > 0.0):
            raise ValueError(f"input dispersion {key!r} = {val!r} must be finite and > 0")
        inputs[str(key)] = fv
    if time_dim not in stats.coords:
        raise ValueError(f"stats has no {time_dim!r} coordinate")

    summary: dict[str, dict[str, Any]] = {}
    for v in _as_names(variables):
        name = f"{v}_dispersion"
        if name not in stats:
            available = sorted(str(k)[: -len("_dispersion")] for k in stats.data_vars if str(k).endswith("_dispersion"))
            raise ValueError(f"no dispersion for {v!r} in stats (looked for {name!r}); available: {available}")
        da = stats[name]
        if da.dims != (time_dim,):
            raise ValueError(
                f"{name} has dimensions {da.dims}; the summary needs ({time_dim!r},) only: select the others first"
            )
        t = np.asarray(da[time_dim].values, dtype=float)
        d = np.asarray(da.values, dtype=float)
        keep = t >= t0
        if not np.any(keep):
            raise ValueError(
                f"no output time >= t_transient = {t0!r} s for {v!r} (times run from {t.min()!r} to {t.max()!r} s)"
            )
        t, d = t[keep], d[keep]
        defined = ~np.isnan(d)
        td, dd = t[defined], d[defined]
        if dd.size == 0:
            tmean = dmax = tmax = None
        else:
            if dd.size == 1 or td[-1] == td[0]:
                tmean = float(dd.mean())
            else:
                tmean = float(np.trapezoid(dd, td) / (td[-1] - td[0]))
            imax = int(np.argmax(dd))
            dmax, tmax = float(dd[imax]), float(td[imax])
        entry: dict[str, Any] = {
            "dispersion_time_mean": tmean,
            "dispersion_max": dmax,
            "time_of_max": tmax,
            "t_start": float(t[0]),
            "t_end": float(t[-1]),
            "n_times": int(t.size),
            "n_undefined": int((~defined).sum()),
            "ratio_time_mean": {k: (None if tmean is None else tmean / x) for k, x in inputs.items()},
            "ratio_max": {k: (None if dmax is None else dmax / x) for k, x in inputs.items()},
        }
        summary[str(v)] = entry
    return summary


def record_start(time: np.ndarray, mean: np.ndarray, t_transient: float, fraction: float = 0.1) -> float:
    """Start of the **whole record** of an observable for its dispersion summary [s].

    A run starts from rest axially (ROP = 0 at t = 0 in every realization), so ``δ = std/|mean|`` is
    undefined at first and meaningless while the mean is close to 0. The whole record starts at the
    first output time after the last time before ``t_transient`` at which ``|mean(t)|`` is below
    ``fraction`` (10 %) of its time average over ``t ≥ t_transient``; at the first output time when it
    never is. ``time`` [s] and ``mean`` (the mean over realizations at each time) have one entry per
    output time.
    """
    t = np.asarray(time, dtype=float)
    m = np.abs(np.asarray(mean, dtype=float))
    steady = t >= t_transient
    reference = float(np.nanmean(m[steady])) if steady.any() else float(np.nanmean(m))
    low = np.nonzero(((m < fraction * reference) | np.isnan(m)) & (t < t_transient))[0]
    if low.size == 0:
        return float(t[0])
    first = int(low[-1]) + 1
    return float(t[min(first, len(t) - 1)])
