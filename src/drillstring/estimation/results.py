"""What the ensemble estimator (:mod:`drillstring.estimation.ensemble`) returns: the downhole state and the
estimated parameters on the record's times, each as the ensemble's mean and its 5, 50 and 95 % quantiles, the
surface channels the ensemble predicted (before each analysis) with their bands, and the run's bookkeeping
(members replaced, samples used); :meth:`EstimationResult.to_dataset` gives an xarray Dataset with units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from drillstring._version import __version__
from drillstring.estimation.surface import CHANNELS

#: The quantiles of every band [-]: the 90 % band and the median.
QUANTILES = (0.05, 0.5, 0.95)

#: The downhole quantities the estimator returns: name -> (unit, long name).
DOWNHOLE = {
    "bit_speed": ("rad/s", "bit rotation speed"),
    "torque_on_bit": ("N*m", "torque the rock applies against the bit's rotation"),
    "force_on_bit": ("N", "axial force of the rock on the bit, upward positive"),
    "rate_of_penetration": ("m/s", "rate of penetration (bit axial velocity, down positive)"),
    "stick_slip_index": ("1", "stick-slip index (max - min)/(2 mean) of the bit speed over the window"),
}


@dataclass
class EstimationResult:
    """The estimate on the record's times (SI units).

    Attributes:
        time: the record's times [s].
        mean: quantity -> (n_time,) ensemble mean (the analysis at each time): the :data:`DOWNHOLE` quantities
            and the estimated parameters (``parameters``).
        quantiles: quantity -> (n_time, 3) the ensemble's :data:`QUANTILES` (5, 50, 95 %).
        units: quantity -> unit (pint spelling), the parameters' included.
        parameters: the estimated parameters' names (keys of ``mean``), in the augmented state's order.
        predicted_mean, predicted_quantiles: surface channel -> the channel as the forecast ensemble predicted it
            at each time, before that time's analysis (the model's prediction, without the measurement noise).
        observed: surface channel -> the record's values [SI]; ``used``: channel -> bool mask of the samples that
            entered an analysis (usable per the record's flags, and a channel the estimator reads).
        replaced: (n_time,) members replaced at each time (a failed or diverging forecast, re-sampled from the
            others); ``stick_slip_window`` [s] the window of the stick-slip index.
        settings: the estimator's settings (a dict of case keys); ``wall_time`` [s] the run's.
        parameter_correlation: ``{(a, b): r}`` the members' correlation of each pair of estimated parameters at
            the record's end (the bit-rock coefficient and the friction factor by their logarithms) [-]: how far
            the record separates them (r near ±1: only a combination of the two is known).
        effective_size: (n_time,) the particle weights' effective sample size ``1/Σ α_i²`` at each analysis of the
            ensemble Kalman particle filter (``particle_share`` > 0), NaN at the other times; None with the ETKF.
        stopped: why the run stopped before the record's end ("" where it ran to the end): interrupted, or the
            ensemble diverged (:class:`~drillstring.estimation.ensemble.EstimateDiverged`); every array then holds
            the samples before the stop.
    """

    time: np.ndarray
    mean: dict[str, np.ndarray]
    quantiles: dict[str, np.ndarray]
    units: dict[str, str]
    parameters: tuple[str, ...]
    predicted_mean: dict[str, np.ndarray]
    predicted_quantiles: dict[str, np.ndarray]
    observed: dict[str, np.ndarray]
    used: dict[str, np.ndarray]
    replaced: np.ndarray
    settings: dict = field(default_factory=dict)
    wall_time: float = 0.0
    source: str = ""
    parameter_correlation: dict = field(default_factory=dict)
    stopped: str = ""
    effective_size: np.ndarray | None = None

    @property
    def replaced_members(self) -> int:
        """Members replaced over the whole run."""
        return int(np.sum(self.replaced))

    def band(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The 90 % band (5 % and 95 % quantiles) of ``name`` on :attr:`time`."""
        q = self.quantiles[name]
        return q[:, 0], q[:, 2]

    def coverage(self, name: str, truth: np.ndarray, start: float = -np.inf) -> float:
        """Fraction of the times at or after ``start`` [s] where ``truth`` (on :attr:`time`) lies within the
        90 % band of ``name`` [-]."""
        low, high = self.band(name)
        keep = self.time >= start
        truth = np.asarray(truth, dtype=float)
        inside = (truth >= low) & (truth <= high)
        return float(np.mean(inside[keep]))

    def to_dataset(self) -> xr.Dataset:
        """The result as an xarray Dataset: per quantity ``<name>`` (ensemble mean, dimension ``time``) and
        ``<name>_quantile`` (dimensions ``time``, ``quantile``), the predicted surface channels as
        ``predicted_<channel>`` and ``predicted_<channel>_quantile``, the record's as ``observed_<channel>``
        with ``used_<channel>``; units in each variable's attrs."""
        data = {}
        for name in self.mean:
            unit = self.units[name]
            long_name = DOWNHOLE.get(name, (unit, f"estimated parameter {name}"))[1]
            data[name] = ("time", self.mean[name], {"units": unit, "long_name": f"{long_name} (ensemble mean)"})
            data[f"{name}_quantile"] = (("time", "quantile"), self.quantiles[name],
                                        {"units": unit, "long_name": f"{long_name} (ensemble quantiles)"})
        for channel in self.predicted_mean:
            unit = CHANNELS[channel]
            data[f"predicted_{channel}"] = ("time", self.predicted_mean[channel],
                                            {"units": unit, "long_name": f"{channel} predicted (ensemble mean)"})
            data[f"predicted_{channel}_quantile"] = (("time", "quantile"), self.predicted_quantiles[channel],
                                                     {"units": unit, "long_name": f"{channel} predicted (quantiles)"})
        for channel, values in self.observed.items():
            data[f"observed_{channel}"] = ("time", values, {"units": CHANNELS[channel],
                                                            "long_name": f"{channel} in the record"})
            data[f"used_{channel}"] = ("time", self.used[channel].astype(np.int8),
                                       {"units": "1", "long_name": f"1 where the {channel} sample was used"})
        data["replaced_members"] = ("time", self.replaced, {"units": "1",
                                                             "long_name": "members re-sampled after a failed forecast"})
        if self.effective_size is not None:
            data["effective_sample_size"] = ("time", self.effective_size, {
                "units": "1", "long_name": "effective sample size of the particle weights at each analysis"})
        coords = {"time": ("time", self.time, {"units": "s"}),
                  "quantile": ("quantile", np.array(QUANTILES), {"units": "1"})}
        attrs = {"drillstring_version": __version__, "source": self.source, "wall_time": float(self.wall_time),
                 "parameters": ",".join(self.parameters)}
        if self.stopped:
            attrs["stopped"] = self.stopped
        attrs.update({f"estimator_{key}": value for key, value in self.settings.items()
                      if isinstance(value, (int, float, str))})
        return xr.Dataset(data, coords=coords, attrs=attrs)
