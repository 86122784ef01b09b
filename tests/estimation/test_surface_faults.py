"""Faults of a surface record (drillstring.estimation.faults): each fault (gap, spike, frozen stretch, unit
error) injected into a clean series is flagged at the samples where it was put, a clean series with realistic
noise is not flagged, and a record the case cannot explain is refused in one line.

(Named test_surface_faults.py: tests/test_faults.py exists, and pytest's default import mode needs distinct
basenames.)

The clean series are the shipped synthetic record's true surface channels (stick-slip under a PI top drive,
drillstring.estimation.synthetic) plus white noise at the synthetic record's levels, and white Gaussian noise.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pytest

from drillstring.case import load_case
from drillstring.estimation import faults
from drillstring.estimation.faults import (
    fill_gaps, flag_faults, frozen, frozen_run_length, noise_sigma, spikes, trend_residual, trend_spikes,
)
from drillstring.estimation.reading import read_surface_record
from drillstring.estimation.surface import FROZEN, MISSING, OUT_OF_RANGE, SPIKE, USABLE
from drillstring.estimation.synthetic import NOISE, read_truth

LBF = 0.45359237 * 9.80665  # N


@pytest.fixture(scope="module")
def case():
    return load_case("stick_slip")


@pytest.fixture(scope="module")
def truth():
    path = resources.files("drillstring").joinpath("cases", "stick_slip_surface_truth.csv")
    return read_truth(path)[1]


def _clean(truth, seed):
    """The true surface channels plus white noise at the synthetic record's levels [SI]."""
    rng = np.random.default_rng(seed)
    return {name: truth[name] + sigma * rng.standard_normal(len(truth["time"])) for name, sigma in NOISE.items()}


def _flags(channels):
    return {name: np.zeros(len(v), dtype=np.int8) for name, v in channels.items()}


# -- an independent Hampel filter: plain loops ------------------------------------------------------------


def _hampel_loops(x, k, threshold, floor):
    out = np.zeros(len(x), dtype=bool)
    for i in range(len(x)):
        if not np.isfinite(x[i]):
            continue
        window = np.array([x[j] for j in range(i - k, i + k + 1) if 0 <= j < len(x) and np.isfinite(x[j])])
        if len(window) <= k:
            continue
        median = np.median(window)
        scale = max(1.482602218505602 * np.median(np.abs(window - median)), floor)
        out[i] = abs(x[i] - median) > threshold * scale
    return out


def test_hampel_filter_equals_a_loop_of_medians():
    rng = np.random.default_rng(5)
    x = rng.standard_normal(600) + np.sin(np.arange(600) / 20.0)
    x[rng.choice(600, 40, replace=False)] = np.nan
    x[rng.choice(600, 15, replace=False)] += rng.choice([-1, 1], 15) * rng.uniform(2, 9, 15)
    for k, threshold, floor in ((10, 6.0, 0.0), (3, 3.0, 0.5), (10, 3.0, 0.2)):
        np.testing.assert_array_equal(spikes(x, k, threshold, floor), _hampel_loops(x, k, threshold, floor))


def test_trend_residual_is_exact_on_piecewise_linear_signals():
    """Corners included: of the six predictions at least four lie on the sample's own line."""
    k = np.arange(200)
    x = np.where(k % 40 < 25, 1.0, -1.6) * 1e3  # steep slopes, N·m per sample
    x = np.cumsum(x)
    e = trend_residual(x)
    np.testing.assert_allclose(e[3:-3], 0.0, atol=1e-9 * np.abs(x).max())
    y = np.random.default_rng(2).standard_normal(12)
    i = 6
    predictions = [2 * y[i - 1] - y[i - 2], 2 * y[i + 1] - y[i + 2], 3 * y[i - 2] - 2 * y[i - 3],
                   3 * y[i + 2] - 2 * y[i + 3], (y[i - 1] + y[i + 1]) / 2, (y[i - 2] + y[i + 2]) / 2]
    assert trend_residual(y)[i] == pytest.approx(y[i] - np.median(predictions))


def test_noise_sigma_ignores_a_steep_trend():
    rng = np.random.default_rng(4)
    t = np.arange(20_000)
    x = 3.0 * rng.standard_normal(len(t)) + 50.0 * np.sin(t / 8.0) + 10.0 * t
    assert noise_sigma(x) == pytest.approx(3.0, rel=0.05)


def test_a_spike_on_a_steep_trend_is_found_against_the_trend(truth):
    rng = np.random.default_rng(8)
    torque = truth["surface_torque"] + NOISE["surface_torque"] * rng.standard_normal(len(truth["time"]))
    steep = int(np.argmax(np.abs(np.diff(truth["surface_torque"]))[20:-20])) + 20
    torque[steep] += 15 * NOISE["surface_torque"]  # 3 kN·m where the torque moves 1.4 kN·m a sample
    assert not spikes(torque)[steep]  # Hampel's window sees the stick-slip swing, not the spike
    assert np.nonzero(trend_spikes(torque))[0].tolist() == [steep]
    torque[300:302] -= 20 * NOISE["surface_torque"]  # two samples: both flagged, not their neighbours
    assert np.nonzero(trend_spikes(torque))[0].tolist() == sorted([steep, 300, 301])


def test_frozen_repeat_probability_matches_quantised_noise():
    """The chance repeat rate p = q / (σ_d √(2π)) of the frozen test against a Monte Carlo of quantised noise."""
    rng = np.random.default_rng(7)
    q, sigma = 0.05, 1.0
    x = np.round(sigma * rng.standard_normal(1_000_000) / q) * q
    observed = np.mean(np.diff(x) == 0.0)
    expected = q / (sigma * math.sqrt(2.0) * math.sqrt(2.0 * math.pi))
    assert observed == pytest.approx(expected, rel=0.02)
    n = 1000
    length = frozen_run_length(x[:n])
    p = max(q / (faults.noise_level(x[:n]) * math.sqrt(2) * math.sqrt(2 * math.pi)), np.mean(np.diff(x[:n]) == 0))
    assert length == max(faults.FROZEN_MIN_SAMPLES, 1 + math.ceil(math.log(faults.FROZEN_FALSE_RUNS / n) / math.log(p)))


# -- clean series: nothing flagged ------------------------------------------------------------------------


def test_clean_stick_slip_series_are_not_flagged(truth, case):
    for seed in range(10):
        channels = _clean(truth, seed)
        flags = _flags(channels)
        notes = flag_faults(truth["time"], channels, flags, case=case)
        assert notes == [], (seed, notes)
        assert all(np.all(f == USABLE) for f in flags.values())


def test_white_noise_is_not_flagged():
    rng = np.random.default_rng(11)
    for _ in range(5):
        x = 1e5 + 1e3 * rng.standard_normal(100_000)
        assert not spikes(x).any()
        assert not frozen(np.round(x, 1))[0].any()


def test_a_quantised_slow_channel_is_not_flagged():
    """A block position logged in whole centimetres while drilling at 10 m/h: long legitimate repeats and
    one-centimetre steps, none a fault; a 5 cm spike on it is one."""
    t = 0.1 * np.arange(6000)
    block = np.round((30.0 - 10.0 / 3600.0 * t + 0.002 * np.random.default_rng(9).standard_normal(len(t))) * 100) / 100
    channels = {"block_position": block.copy()}
    flags = _flags(channels)
    assert flag_faults(t, channels, flags) == [] and not flags["block_position"].any()
    channels["block_position"][3000] += 0.05
    flags = _flags(channels)
    flag_faults(t, channels, flags)
    assert np.nonzero(flags["block_position"])[0].tolist() == [3000]


# -- each fault, injected, flagged where it is ------------------------------------------------------------


def test_a_gap_inserts_missing_samples_and_keeps_its_neighbours(tmp_path):
    t = 0.1 * np.arange(100)
    kept = np.ones(100, dtype=bool)
    kept[40:52] = False
    full, measured, gaps = fill_gaps(t[kept])
    np.testing.assert_allclose(full, t, atol=1e-9)
    assert np.nonzero(measured < 0)[0].tolist() == list(range(40, 52))
    assert gaps == [(pytest.approx(3.9), pytest.approx(5.2), 12)]
    rng = np.random.default_rng(0)
    text = "TIME [s],HKLD [kN]\n" + "".join(f"{t[k]:.1f},{1664 + rng.standard_normal():.3f}\n" for k in range(100)
                                             if kept[k])
    path = tmp_path / "gap.csv"
    path.write_text(text, encoding="utf-8")
    record = read_surface_record(path)
    assert np.nonzero(record.flags["hook_load"] == MISSING)[0].tolist() == list(range(40, 52))
    assert np.all(record.flags["hook_load"][[39, 52]] == USABLE)
    assert [n for n in record.notes if n.startswith("gap")] == [
        "gap from 3.9 s to 5.2 s: 12 missing sample(s) inserted in every channel"]


def test_a_spike_is_flagged_at_its_sample(truth, case):
    channels = _clean(truth, 1)
    channels["hook_load"][200] -= 30e3  # 30 sigma
    channels["surface_torque"][500] += 30e3  # far beyond the stick-slip swing
    channels["top_speed"][300:302] += 2.0  # two samples, 100 sigma
    flags = _flags(channels)
    notes = flag_faults(truth["time"], channels, flags, case=case)
    assert np.nonzero(flags["hook_load"])[0].tolist() == [200]
    assert np.nonzero(flags["surface_torque"])[0].tolist() == [500]
    assert np.nonzero(flags["top_speed"])[0].tolist() == [300, 301]
    assert all(np.all(f[f != 0] == SPIKE) for f in flags.values())
    assert len(notes) == 3 and all("spike" in n for n in notes)


def test_a_frozen_stretch_is_flagged_and_a_short_repeat_is_not(truth, case):
    channels = {name: np.round(v, 6) for name, v in _clean(truth, 2).items()}
    channels["top_speed"][100:130] = channels["top_speed"][100]
    channels["hook_load"][400:403] = channels["hook_load"][400]  # 3 repeats: below the run length
    flags = _flags(channels)
    notes = flag_faults(truth["time"], channels, flags, case=case)
    assert np.nonzero(flags["top_speed"] == FROZEN)[0].tolist() == list(range(100, 130))
    assert not flags["hook_load"].any()
    assert notes == ["top_speed: 30 sample(s) frozen (runs of 5 or more identical values) at t = 10-12.9 s"]


@pytest.mark.parametrize("channel, header_unit, true_unit", [
    ("hook_load", "kN", "klbf"),
    ("hook_load", "N", "lbf"),
    ("surface_torque", "N*m", "kN*m"),
    ("top_speed", "rpm", "rad/s"),
    ("block_position", "m", "mm"),
])
def test_a_unit_error_is_flagged_out_of_range_naming_the_unit(truth, case, channel, header_unit, true_unit):
    from drillstring.units import unit_factor

    channels = _clean(truth, 3)
    dim = faults.DIMENSION[channel]
    # the file holds the values in true_unit but its header says header_unit
    channels[channel] = channels[channel] / unit_factor(true_unit, dim) * unit_factor(header_unit, dim)
    flags = _flags(channels)
    notes = flag_faults(truth["time"], channels, flags, units={channel: header_unit}, case=case)
    assert np.all(flags[channel] == OUT_OF_RANGE)
    assert all(not f.any() for name, f in flags.items() if name != channel)
    assert len(notes) == 1 and f"the values look like {true_unit}, not {header_unit}" in notes[0]


def test_a_standpipe_pressure_in_psi_read_as_pascal_is_found_without_a_case():
    t = 0.1 * np.arange(300)
    spp = {"standpipe_pressure": 3000.0 + 5.0 * np.random.default_rng(0).standard_normal(300)}  # psi, header Pa
    flags = _flags(spp)
    notes = flag_faults(t, spp, flags, units={"standpipe_pressure": "Pa"})
    assert np.all(flags["standpipe_pressure"] == OUT_OF_RANGE) and "look like psi" in notes[0]
    spp = {"standpipe_pressure": 3000.0 * 6894.757 + 3e4 * np.random.default_rng(0).standard_normal(300)}
    assert flag_faults(t, spp, _flags(spp)) == []


def test_a_unit_error_read_from_a_file_is_flagged(tmp_path, truth, case):
    hook = _clean(truth, 4)["hook_load"] / (1e3 * LBF)  # klbf written under a kN header
    path = tmp_path / "hook.csv"
    path.write_text("TIME [s],HKLD [kN]\n" + "".join(f"{t:.2f},{h:.4f}\n" for t, h in zip(truth["time"], hook)),
                    encoding="utf-8")
    record = read_surface_record(path, case=case)
    assert np.all(record.flags["hook_load"] == OUT_OF_RANGE)
    assert not record.usable("hook_load").any()
    fixed = read_surface_record(path, case=case, units={"hook_load": "klbf"})
    assert np.all(fixed.flags["hook_load"] == USABLE)


# -- what the case cannot explain -------------------------------------------------------------------------


def test_a_hook_load_above_the_weight_in_air_is_refused(truth, case):
    air = case.weight  # buoyancy off in this case: the weight is the weight in air
    channels = _clean(truth, 5)
    channels["hook_load"] = 1.1 * air + channels["hook_load"] - channels["hook_load"].mean()
    with pytest.raises(ValueError, match=r"^hook_load: \d+ of 801 samples are above 1853 kN \(1.05 times the "
                                         r"string's weight in air\): the record does not fit the case$"):
        flag_faults(truth["time"], channels, _flags(channels), case=case)


def test_a_few_hook_loads_above_the_weight_in_air_are_out_of_range(truth, case):
    channels = _clean(truth, 6)
    channels["hook_load"][[10, 11, 12]] = 1.2 * case.weight
    flags = _flags(channels)
    notes = flag_faults(truth["time"], channels, flags, case=case)
    assert np.nonzero(flags["hook_load"])[0].tolist() == [10, 11, 12]
    assert np.all(flags["hook_load"][[10, 11, 12]] == OUT_OF_RANGE)
    assert notes == ["hook_load: 3 sample(s) outside [0, 1.853e+06] flagged out of range"]


@pytest.mark.parametrize("channel, scale, shift, message", [
    ("top_speed", 0.03, 0.0, (r"top_speed \(column RPM\): median 0.314\d rad/s, outside the case's set point, 100 rpm, "
                              r"and no usual unit explains it: the record does not fit the case")),
    ("hook_load", 1.0, -1.8e6, (r"hook_load \(column RPM\): median -1.357e\+05 N, outside the case's hook load while "
                                r"drilling, 1664 kN .*, and no usual unit explains it")),
])
def test_a_median_no_unit_explains_is_refused(truth, case, channel, scale, shift, message):
    channels = _clean(truth, 7)
    channels[channel] = channels[channel] * scale + shift
    with pytest.raises(ValueError, match=message):
        flag_faults(truth["time"], channels, _flags(channels), columns={channel: "RPM"}, case=case)
