"""The faults of a surface record, found and flagged so that none is used silently (docs/estimation.md,
"Surface records"). Each test works on arrays in SI units on the record's time axis; each fault it finds
writes one line of the record's notes.

Gaps (:func:`fill_gaps`)
    A time step longer than :data:`GAP_FACTOR` times the record's typical step (the median step) is a gap:
    the samples that should be there are missing. Reading inserts them, evenly spaced at about the typical step,
    with NaN values flagged ``MISSING`` (every channel); the measured samples on either side are kept and usable.
    A filter stepping through the record then forecasts across the gap without an update. An empty or
    non-numeric cell (or the LAS null value -999.25) is NaN, flagged ``MISSING`` in its channel.

Spikes (:func:`spikes`, :func:`trend_spikes`)
    Two tests; a sample either flags is a spike (``SPIKE``).

    - Hampel's filter (:func:`spikes`): a sample deviating from the median of the :data:`HAMPEL_HALF_WINDOW`
      samples on either side by more than :data:`HAMPEL_THRESHOLD` robust standard deviations, ``1.4826 MAD``
      of that window (the median absolute deviation, scaled to a normal law's σ), is a spike. The scale is at
      least the channel's own noise level (:func:`noise_level`) and its resolution (:func:`resolution`), so
      that a quiet or quantised stretch (MAD 0) flags no ordinary step. Robust to wide excursions, but blind to a spike smaller than the signal's own
      swing over the window (a stick-slip torque swings by ±10 kN·m within the 2 s window at 10 Hz).
    - Against the local trend (:func:`trend_spikes`): each sample is compared with the median of six
      predictions from its neighbours (linear extrapolations from the two samples on its left, on its right,
      and from the two beyond them; the means of its two neighbours and of the two beyond), exact on any
      piecewise-linear signal, corners included. A residual above :data:`TREND_THRESHOLD` times the channel's
      noise σ (from its second differences, :func:`noise_sigma`, insensitive to the trend; at least the rounding
      noise q/√12 of the resolution q) marks a candidate;
      the largest candidate within ±3 samples is flagged and removed, and the test repeats (at most
      :data:`TREND_ITERATIONS` times), so that a spike's neighbours, whose predictions it spoils, are not
      flagged with it.

Frozen stretches (:func:`frozen`)
    A run of identical consecutive values. A channel with noise σ_d between samples (the robust σ of its
    first differences), logged at resolution q (its smallest nonzero step), repeats a value by chance with
    probability about ``p = q / (σ_d √(2π))``, or at least the fraction of repeats observed over the record
    (a slowly varying channel logged coarsely repeats often, legitimately). A run of L equal samples has
    probability about ``p^(L−1)`` at each start, so a run of at least
    ``L* = max(FROZEN_MIN_SAMPLES, 1 + ⌈ln(FROZEN_FALSE_RUNS / N) / ln p⌉)`` samples is expected by chance
    fewer than :data:`FROZEN_FALSE_RUNS` times in the record's N samples: such runs are flagged ``FROZEN``.
    A channel identical over the whole record is frozen throughout.

Values the case cannot explain (:func:`check_against_case`)
    Each channel's median is compared with what the case expects (:func:`case_expectations`): the hook load
    near the case's hook load while drilling (the string's weight, buoyed when the case's ``model.buoyancy``
    is on, less the weight on bit: between 1/1.5 and 1.5 times it), the top speed near the set point (1/2 to
    2 times), the surface torque near the bit's steady torque at the set point (1/10 to 10 times; this
    catches a factor 1000, not the factor 1.356 between N·m and ft·lbf), the block position between −10 and
    60 m and the standpipe pressure between 0.1 and 70 MPa (these two without a case too). A median outside its
    band that a usual unit of the channel (:data:`UNIT_CANDIDATES`) brings inside is a unit error: the channel
    is flagged ``OUT_OF_RANGE`` throughout, with a note naming the likely unit. A median that no usual unit
    explains makes the record one the case cannot explain: ``ValueError``. Sample by sample, a hook load
    below 0 or above 1.05 times the string's weight in air is ``OUT_OF_RANGE``; above (or below) over more
    than half of the record, the record is refused.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from drillstring.estimation.surface import CHANNELS, FROZEN, MISSING, OUT_OF_RANGE, SPIKE, USABLE
from drillstring.units import ANGULAR_SPEED, FORCE, LENGTH, PRESSURE, TORQUE, Dimension, unit_factor

__all__ = [
    "DIMENSION",
    "Expectation",
    "FROZEN_FALSE_RUNS",
    "FROZEN_MIN_SAMPLES",
    "GAP_FACTOR",
    "HAMPEL_HALF_WINDOW",
    "HAMPEL_THRESHOLD",
    "TREND_THRESHOLD",
    "UNIT_CANDIDATES",
    "case_expectations",
    "check_against_case",
    "fill_gaps",
    "flag_faults",
    "frozen",
    "frozen_run_length",
    "missing_note",
    "noise_level",
    "noise_sigma",
    "resolution",
    "spikes",
    "trend_spikes",
]

#: A time step longer than this many typical (median) steps is a gap.
GAP_FACTOR = 3.0
#: Hampel's filter: samples on either side of the tested one.
HAMPEL_HALF_WINDOW = 10
#: Hampel's filter: a spike deviates from the window's median by more than this many robust σ (1.4826 MAD).
HAMPEL_THRESHOLD = 6.0
#: The test against the local trend: a spike's residual exceeds this many noise σ (the residual of white noise has
#: a standard deviation of 1.25 σ).
TREND_THRESHOLD = 8.0
#: The test against the local trend: most passes (each flags the largest residual of each cluster).
TREND_ITERATIONS = 20
#: The median absolute deviation of a normal law is σ / 1.4826.
MAD_SCALE = 1.482602218505602
#: The shortest run of identical values ever flagged frozen [samples].
FROZEN_MIN_SAMPLES = 5
#: Expected number of runs flagged frozen by chance, per channel and record (sets the run length).
FROZEN_FALSE_RUNS = 0.01
#: Most samples of a record, gaps filled.
MAX_SAMPLES = 5_000_000
#: A hook load above this many times the string's weight in air is out of range.
AIR_WEIGHT_MARGIN = 1.05

#: The dimension of each channel (and of ``time``).
DIMENSION: dict[str, Dimension] = {
    "top_speed": ANGULAR_SPEED,
    "surface_torque": TORQUE,
    "hook_load": FORCE,
    "block_position": LENGTH,
    "standpipe_pressure": PRESSURE,
}

#: The usual units of each channel, tried when its values do not fit the unit given.
UNIT_CANDIDATES: dict[str, tuple[str, ...]] = {
    "top_speed": ("rad/s", "rpm", "Hz", "deg/s"),
    "surface_torque": ("N*m", "kN*m", "daN*m", "ft*lbf", "kft*lbf"),
    "hook_load": ("N", "kN", "daN", "kgf", "tf", "lbf", "klbf"),
    "block_position": ("m", "cm", "mm", "ft", "in"),
    "standpipe_pressure": ("Pa", "kPa", "MPa", "bar", "psi", "ksi"),
}


# ---------------------------------------------------------------------------------------------------------
# Gaps
# ---------------------------------------------------------------------------------------------------------


def typical_step(time: np.ndarray) -> float:
    """The record's typical time step [s]: the median of its steps."""
    return float(np.median(np.diff(time)))


def fill_gaps(time: np.ndarray, factor: float = GAP_FACTOR) -> tuple[np.ndarray, np.ndarray, list[tuple[float, float, int]]]:
    """The time axis with the samples of its gaps inserted (module docstring).

    Returns ``(time, measured, gaps)``: the new times [s]; for each, the index of the measured sample it is in
    ``time`` (−1 for an inserted one); the gaps as ``(start, end, samples inserted)``.
    """
    time = np.asarray(time, dtype=float)
    steps = np.diff(time)
    step = typical_step(time)
    at = np.nonzero(steps > factor * step)[0]
    counts = np.maximum(np.rint(steps[at] / step).astype(np.int64) - 1, 1)
    total = len(time) + int(counts.sum())
    if total > MAX_SAMPLES:
        worst = int(at[np.argmax(counts)])
        raise ValueError(f"the gaps of the record would need {total:,} samples at its typical step {step:g} s, more "
                         f"than the {MAX_SAMPLES:,} allowed (the longest gap: {time[worst]:g} s to {time[worst + 1]:g} s)")
    pieces, index, gaps = [], [], []
    start = 0
    for i, count in zip(at, counts):
        pieces.append(time[start:i + 1])
        index.append(np.arange(start, i + 1))
        inserted = time[i] + (time[i + 1] - time[i]) * np.arange(1, count + 1) / (count + 1)
        pieces.append(inserted)
        index.append(np.full(count, -1))
        gaps.append((float(time[i]), float(time[i + 1]), int(count)))
        start = i + 1
    pieces.append(time[start:])
    index.append(np.arange(start, len(time)))
    return np.concatenate(pieces), np.concatenate(index), gaps


# ---------------------------------------------------------------------------------------------------------
# Spikes and frozen stretches
# ---------------------------------------------------------------------------------------------------------


def noise_level(values: np.ndarray) -> float:
    """The channel's noise σ [its unit], robustly: ``1.4826 MAD`` of its first differences over √2 (white
    noise of σ has differences of σ√2; a smooth signal adds little to most differences). 0 when fewer than two
    consecutive finite samples."""
    d = np.diff(np.asarray(values, dtype=float))
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return 0.0
    return float(MAD_SCALE * np.median(np.abs(d - np.median(d))) / math.sqrt(2.0))


def spikes(values: np.ndarray, half_window: int = HAMPEL_HALF_WINDOW, threshold: float = HAMPEL_THRESHOLD,
           floor: float | None = None) -> np.ndarray:
    """Boolean mask of the spikes of ``values`` (NaN: not tested, not used) by Hampel's filter (module docstring):
    ``|x_i − median| > threshold · max(1.4826 MAD, floor)`` over the ``2 half_window + 1`` samples centred on i
    (the finite ones; at least ``half_window`` of them). ``floor`` defaults to the larger of :func:`noise_level`
    and the resolution (:func:`resolution`: a step of one resolution is never a spike)."""
    x = np.asarray(values, dtype=float)
    n = len(x)
    if floor is None:
        floor = max(noise_level(x), resolution(x))
    out = np.zeros(n, dtype=bool)
    padded = np.concatenate([np.full(half_window, np.nan), x, np.full(half_window, np.nan)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half_window + 1)
    chunk = 100_000
    for a in range(0, n, chunk):
        w = windows[a:a + chunk]
        centre = x[a:a + chunk]
        enough = np.sum(np.isfinite(w), axis=1) > half_window
        rows = np.nonzero(enough & np.isfinite(centre))[0]
        if not len(rows):
            continue
        w = w[rows]
        median = np.nanmedian(w, axis=1)
        mad = np.nanmedian(np.abs(w - median[:, None]), axis=1)
        scale = np.maximum(MAD_SCALE * mad, floor)
        out[a + rows] = np.abs(centre[rows] - median) > threshold * scale
    return out


def resolution(values: np.ndarray) -> float:
    """The channel's resolution q [its unit]: its smallest nonzero step between consecutive finite samples (the
    logging's quantum for a quantised channel; tiny for one logged with every digit); 0 when it never changes."""
    d = np.abs(np.diff(np.asarray(values, dtype=float)))
    d = d[np.isfinite(d) & (d > 0.0)]
    return float(d.min()) if len(d) else 0.0


def noise_sigma(values: np.ndarray) -> float:
    """The channel's white-noise σ [its unit] from its second differences, ``1.4826 MAD / √6`` (white noise of σ
    has second differences of σ√6; a trend, even a steep one, adds only its curvature). 0 when fewer than three
    consecutive finite samples."""
    d = np.diff(np.asarray(values, dtype=float), 2)
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return 0.0
    return float(MAD_SCALE * np.median(np.abs(d - np.median(d))) / math.sqrt(6.0))


def _shifted(x: np.ndarray, k: int) -> np.ndarray:
    """``x[i - k]`` at i (NaN outside)."""
    out = np.full(len(x), np.nan)
    if k > 0:
        out[k:] = x[:-k]
    else:
        out[:k] = x[-k:]
    return out


def trend_residual(values: np.ndarray) -> np.ndarray:
    """Each sample less the median of its six predictions from its neighbours (module docstring): ``2x[i−1] −
    x[i−2]``, ``2x[i+1] − x[i+2]``, ``3x[i−2] − 2x[i−3]``, ``3x[i+2] − 2x[i+3]``, ``(x[i−1] + x[i+1])/2``,
    ``(x[i−2] + x[i+2])/2``, those with a NaN left out (NaN where none is left)."""
    x = np.asarray(values, dtype=float)
    s = {k: _shifted(x, k) for k in (-3, -2, -1, 1, 2, 3)}
    predictions = np.array([2 * s[1] - s[2], 2 * s[-1] - s[-2], 3 * s[2] - 2 * s[3], 3 * s[-2] - 2 * s[-3],
                            (s[1] + s[-1]) / 2, (s[2] + s[-2]) / 2])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN column: NaN, as wanted
        return x - np.nanmedian(predictions, axis=0)


def trend_spikes(values: np.ndarray, threshold: float = TREND_THRESHOLD, sigma: float | None = None,
                 iterations: int = TREND_ITERATIONS) -> np.ndarray:
    """Boolean mask of the spikes of ``values`` against their local trend (module docstring): repeatedly, the
    samples whose :func:`trend_residual` exceeds ``threshold · sigma`` and is the largest within ±3 samples are
    flagged and removed. ``sigma`` defaults to :func:`noise_sigma` of the values, or the resolution's rounding
    noise ``q/√12`` (:func:`resolution`) if larger."""
    x = np.array(values, dtype=float)
    if sigma is None:
        sigma = max(noise_sigma(x), resolution(x) / math.sqrt(12.0))
    out = np.zeros(len(x), dtype=bool)
    if not sigma > 0.0:
        return out
    for _ in range(iterations):
        e = np.abs(trend_residual(x))
        e[~np.isfinite(e)] = 0.0
        candidates = e > threshold * sigma
        if not candidates.any():
            break
        padded = np.concatenate([np.zeros(3), e, np.zeros(3)])
        largest = np.lib.stride_tricks.sliding_window_view(padded, 7).max(axis=1)
        picked = candidates & (e >= largest)
        out |= picked
        x[picked] = np.nan
    return out


def frozen_run_length(values: np.ndarray, false_runs: float = FROZEN_FALSE_RUNS,
                      min_samples: int = FROZEN_MIN_SAMPLES) -> float:
    """The shortest run of identical values that noise does not explain [samples] (module docstring); inf when
    the channel repeats values too often to tell."""
    x = np.asarray(values, dtype=float)
    d = np.diff(x)
    d = d[np.isfinite(d)]
    n = int(np.sum(np.isfinite(x)))
    if len(d) == 0:
        return math.inf
    sigma_d = noise_level(x) * math.sqrt(2.0)
    p_model = resolution(x) / (sigma_d * math.sqrt(2.0 * math.pi)) if sigma_d > 0.0 else 1.0
    p = max(p_model, float(np.mean(d == 0.0)))
    if p >= 1.0:
        return math.inf
    if p <= 0.0:
        return float(min_samples)
    return float(max(min_samples, 1 + math.ceil(math.log(false_runs / max(n, 1)) / math.log(p))))


def frozen(values: np.ndarray, false_runs: float = FROZEN_FALSE_RUNS,
           min_samples: int = FROZEN_MIN_SAMPLES) -> tuple[np.ndarray, float]:
    """``(mask, L*)``: the samples in runs of at least ``L*`` identical consecutive finite values
    (:func:`frozen_run_length`; a NaN ends a run) and ``L*``. A channel of at least ``min_samples`` finite
    samples, all identical, is frozen throughout (``L*`` is then its length)."""
    x = np.asarray(values, dtype=float)
    finite = np.isfinite(x)
    mask = np.zeros(len(x), dtype=bool)
    if finite.sum() >= min_samples and np.all(x[finite] == x[finite][0]):
        mask[finite] = True
        return mask, float(finite.sum())
    length = frozen_run_length(x, false_runs, min_samples)
    if not math.isfinite(length):
        return mask, length
    same = finite[1:] & finite[:-1] & (x[1:] == x[:-1])
    # runs of True in `same` of k entries are runs of k + 1 equal samples
    edges = np.diff(np.concatenate([[0], same.astype(np.int8), [0]]))
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    for s, e in zip(starts, ends):
        if e - s + 1 >= length:
            mask[s:e + 1] = True
    return mask, length


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]))


def _where(time: np.ndarray, mask: np.ndarray, most: int = 3) -> str:
    """The times of the runs of ``mask``, the first few: ``t = 35.1 s, 40.2-43.1 s``."""
    runs = _runs(mask)
    shown = [f"{time[a]:.6g} s" if b - a == 1 else f"{time[a]:.6g}-{time[b - 1]:.6g} s" for a, b in runs[:most]]
    more = f" and {len(runs) - most} more" if len(runs) > most else ""
    return "t = " + ", ".join(shown) + more


# ---------------------------------------------------------------------------------------------------------
# What the case expects
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Expectation:
    """What a case expects of a channel [SI].

    Attributes:
        low, high: the band of the channel's median.
        centre: the most likely median (ranks the units that would explain a median outside the band).
        what: the expectation in words, for messages.
        sample_low, sample_high: bounds of every sample (None: none).
    """

    low: float
    high: float
    centre: float
    what: str
    sample_low: float | None = None
    sample_high: float | None = None


def _weight_in_air(case) -> float:
    from drillstring.derived import axial_load_per_length, string_axial_load

    g = case.environment.gravity if case.model.gravity else 0.0
    loads = [axial_load_per_length(steel_density=case.material_of(s).density, area=s.area, gravity=g,
                                   buoyancy_density=0.0, skin_friction=0.0) for s in case.sections]
    return string_axial_load(loads, [s.length for s in case.sections])


def case_expectations(case=None) -> dict[str, Expectation]:
    """What ``case`` (a :class:`~drillstring.case.Case`; None: only the bands that need no case) expects of each
    channel (module docstring)."""
    out = {
        "block_position": Expectation(-10.0, 60.0, 25.0, "a block height between -10 and 60 m"),
        "standpipe_pressure": Expectation(1e5, 7e7, 1.5e7, "a standpipe pressure between 0.1 and 70 MPa"),
    }
    if case is None:
        return out
    hook = case.weight_on_hook
    air = _weight_in_air(case)
    if hook > 0.0:
        out["hook_load"] = Expectation(hook / 1.5, hook * 1.5, hook,
                                       f"the case's hook load while drilling, {hook / 1e3:.4g} kN (weight "
                                       f"{case.weight / 1e3:.4g} kN less {case.operation.weight_on_bit / 1e3:.4g} kN "
                                       "on bit)", 0.0, AIR_WEIGHT_MARGIN * air)
    speed = case.operation.top_speed
    if speed > 0.0:
        out["top_speed"] = Expectation(speed / 2.0, speed * 2.0, speed,
                                       f"the case's set point, {speed * 30.0 / math.pi:.4g} rpm")
    torque = _steady_torque(case)
    if torque:
        out["surface_torque"] = Expectation(torque / 10.0, torque * 10.0, torque,
                                            f"the bit's steady torque at the set point, {torque / 1e3:.4g} kN·m")
    return out


def _steady_torque(case) -> float | None:
    """|torque on bit| [N·m] of steady drilling at the case's set point and weight on bit, if its law says."""
    from drillstring.forces.bit_rock import case_bit_rock

    try:
        law = case_bit_rock(case)
        steady = law.steady_drilling(case.operation.top_speed, case.operation.weight_on_bit, 0.0)
    except (AttributeError, NotImplementedError, ValueError, TypeError):
        return None
    if steady is None or not math.isfinite(steady.torque) or steady.torque == 0.0:
        return None
    return abs(float(steady.torque))


def check_against_case(name: str, values: np.ndarray, unit: str, expectation: Expectation, *,
                       column: str = "", source: str = "") -> tuple[np.ndarray, str | None]:
    """``(mask, note)``: the samples of channel ``name`` (``values`` [SI], read in ``unit`` from ``column``)
    out of range, and the note saying why (None when none), as the module docstring says; ``ValueError`` (one
    line) for values the case cannot explain."""
    x = np.asarray(values, dtype=float)
    finite = np.isfinite(x)
    mask = np.zeros(len(x), dtype=bool)
    if not finite.any():
        return mask, None
    where = f"{source + ': ' if source else ''}{name}{f' (column {column})' if column else ''}"
    median = float(np.median(x[finite]))
    e = expectation
    if not e.low <= median <= e.high:
        given = unit_factor(unit, DIMENSION[name])
        fits = []  # (distance from the expected median in log, unit) of the units that bring the median in
        for candidate in UNIT_CANDIDATES[name]:
            ratio = unit_factor(candidate, DIMENSION[name]) / given  # SI of one value in candidate / in unit
            corrected = median * ratio
            if abs(ratio - 1.0) > 1e-9 and e.low <= corrected <= e.high:
                distance = abs(math.log(corrected / e.centre)) if corrected * e.centre > 0.0 else math.inf
                fits.append((distance, candidate))
        shown = f"{median / given:.4g} {unit}"
        if not fits:
            raise ValueError(f"{where}: median {shown}, outside {e.what}, and no usual unit explains it: the record "
                             "does not fit the case (check the column, its unit and the case)")
        likely = min(fits)[1]
        mask[:] = True
        return mask, (f"{name}: median {shown} is outside {e.what}; the values look like {likely}, not {unit}: "
                      f"flagged out of range throughout (read with units={{'{name}': '{likely}'}} if so)")
    low = -math.inf if e.sample_low is None else e.sample_low
    high = math.inf if e.sample_high is None else e.sample_high
    out = finite & ((x < low) | (x > high))
    if out.sum() > 0.5 * finite.sum():
        above = int(np.sum(finite & (x > high)))
        side = f"above {high / 1e3:.4g} kN ({AIR_WEIGHT_MARGIN:g} times the string's weight in air)" if above \
            else f"below {low:g}"
        raise ValueError(f"{where}: {int(out.sum()):,} of {int(finite.sum()):,} samples are {side}: the record "
                         "does not fit the case")
    if out.any():
        return out, f"{name}: {int(out.sum())} sample(s) outside [{low:.4g}, {high:.4g}] flagged out of range"
    return mask, None


# ---------------------------------------------------------------------------------------------------------
# All together
# ---------------------------------------------------------------------------------------------------------


def flag_faults(time: np.ndarray, channels: dict[str, np.ndarray], flags: dict[str, np.ndarray], *,
                units: dict[str, str] | None = None, columns: dict[str, str] | None = None, case=None,
                source: str = "") -> list[str]:
    """Flag, in place in ``flags`` (int8 codes of :data:`~drillstring.estimation.surface.FLAGS`), the faults of
    ``channels`` (SI values on ``time``) that the module docstring lists, except gaps (:func:`fill_gaps`, done
    before); returns the notes, one line per fault found. A sample already flagged keeps its flag. Values out of
    range are tested first (on every finite sample), then frozen stretches, then spikes (on what is left).
    ``units`` and ``columns``: each channel's unit as read and its column, for the messages (default: SI, the
    channel's name). Raises ``ValueError`` for values the case cannot explain."""
    units = units or {}
    columns = columns or {}
    expectations = case_expectations(case)
    notes = []
    for name, values in channels.items():
        x = np.asarray(values, dtype=float)
        flag = flags[name]
        flag[~np.isfinite(x) & (flag == USABLE)] = MISSING
        if name in expectations:
            mask, note = check_against_case(name, x, units.get(name, CHANNELS[name]), expectations[name],
                                            column=columns.get(name, ""), source=source)
            flag[mask & (flag == USABLE)] = OUT_OF_RANGE
            if note:
                notes.append(note)
        usable = np.where(flag == USABLE, x, np.nan)
        mask, length = frozen(usable)
        if mask.any():
            flag[mask] = FROZEN
            notes.append(f"{name}: {int(mask.sum())} sample(s) frozen (runs of {length:g} or more identical values) "
                         f"at {_where(time, mask)}")
        usable = np.where(flag == USABLE, x, np.nan)
        mask = spikes(usable) | trend_spikes(usable)
        if mask.any():
            flag[mask] = SPIKE
            notes.append(f"{name}: {int(mask.sum())} spike(s) (Hampel, {2 * HAMPEL_HALF_WINDOW + 1} samples, "
                         f"{HAMPEL_THRESHOLD:g} robust σ, or {TREND_THRESHOLD:g} noise σ off the local trend) at "
                         f"{_where(time, mask)}")
    return notes


def missing_note(name: str, time: np.ndarray, mask: np.ndarray) -> str:
    """The note of the empty or non-numeric cells ``mask`` of channel ``name``."""
    return f"{name}: {int(mask.sum())} empty or non-numeric cell(s) flagged missing at {_where(time, mask)}"
