"""The start of a run in its summaries (docs/model.md §8): when the bit speed's oscillation has settled,
measured on the run, and how long the rate of penetration was negative under the ramped weight on bit."""

import math

import numpy as np
import pytest
import xarray as xr

from drillstring.dynamics.simulate import settling_time, start_facts

OMEGA = 4 * math.pi  # 120 rpm [rad/s]
PERIOD = 3.0  # [s]


def _growing_then_steady(t, settles_at):
    """A bit speed oscillating at PERIOD whose amplitude grows linearly from 0.1 Ω at 10 s to 0.9 Ω at
    ``settles_at``, then stays."""
    amplitude = np.interp(t, [10.0, settles_at], [0.1 * OMEGA, 0.9 * OMEGA])
    return OMEGA + amplitude * np.sin(2 * math.pi * t / PERIOD)


def test_settling_time_finds_where_a_growing_oscillation_stops_growing():
    t = np.arange(0.0, 60.0, 0.01)
    for settles_at in (20.0, 30.0):
        found = settling_time(t, _growing_then_steady(t, settles_at), OMEGA, start=10.0)
        # within the last period of the growth (a range within 15 % of the final one) and never after it
        assert settles_at - 2 * PERIOD <= found <= settles_at + 1e-9, (settles_at, found)


def test_settling_time_of_a_decay_to_steady_drilling_and_of_a_run_that_never_settles():
    t = np.arange(0.0, 60.0, 0.01)
    decaying = OMEGA + 0.5 * OMEGA * np.exp(-(t - 10.0) / 4.0) * np.sin(2 * math.pi * t / PERIOD)
    found = settling_time(t, decaying, OMEGA, start=10.0)
    # the range 2 A e^(-(t-10)/4) falls below 1 % of Ω (the floor) after about 4 ln(100) = 18 s
    assert 10.0 + 4 * math.log(100.0) - 2 * PERIOD <= found <= 10.0 + 4 * math.log(100.0) + PERIOD
    growing = OMEGA + 0.01 * OMEGA * np.exp((t - 10.0) / 10.0) * np.sin(2 * math.pi * t / PERIOD)
    assert math.isnan(settling_time(t, growing, OMEGA, start=10.0))
    assert math.isnan(settling_time(t[:500], decaying[:500], OMEGA, start=0.0))  # under 3 periods' worth


def test_start_facts_time_of_negative_rop_and_window_before_settling():
    t = np.arange(0.0, 60.0, 0.01)
    force = 25e3 * np.minimum(t / 10.0, 1.0)
    rop = 1e-3 * (force / 7e3 - 1.0)  # negative below 7 kN: until t = 2.8 s
    facts = start_facts(t, {"rate_of_penetration": rop, "force_on_bit": force,
                            "bit_speed": _growing_then_steady(t, 25.0)}, 10.0, 10.0, OMEGA)
    assert facts.negative_rop_until == pytest.approx(2.79, abs=1e-9)
    assert facts.force_on_bit_then == pytest.approx(25e3 * 0.279)
    assert facts.window_before_settled and 19.0 <= facts.settled <= 25.0
    steady = start_facts(t, {"rate_of_penetration": np.full_like(t, 1e-3), "force_on_bit": force,
                             "bit_speed": np.full_like(t, OMEGA)}, 10.0, 10.0, OMEGA)
    assert math.isnan(steady.negative_rop_until) and not steady.window_before_settled


def test_simulate_summaries_of_a_ramped_start_begin_when_the_oscillation_settled():
    """`drillstring simulate`'s window: after a ramped start, from the measured settling time when it is
    later than min(10 s, t_end/2), with a note; a note on the negative ROP; nothing for a start on bottom."""
    from drillstring.case import load_case
    from drillstring.cli.simulate import _start_window

    t = np.arange(0.0, 60.0, 0.01)
    force = 25e3 * np.minimum(t / 10.0, 1.0)
    ds = xr.Dataset({"rate_of_penetration": ("time", 1e-3 * (force / 7e3 - 1.0)),
                     "force_on_bit": ("time", force), "bit_speed": ("time", _growing_then_steady(t, 30.0))},
                    coords={"time": t})
    reference = load_case("reference")
    ramped = reference.model_copy(update={
        "initial": reference.initial.model_copy(update={"start": "ramp"}),
        "operation": reference.operation.model_copy(update={"top_speed": OMEGA})})
    start, notes = _start_window(ramped, ds, 10.0, "si")
    assert 30.0 - 2 * PERIOD <= start <= 30.0 and len(notes) == 2
    assert "negative until t = 2.79 s" in notes[0] and "Tucker–Wang" in notes[0]
    assert notes[1].startswith(f"summaries from t = {start:.2f} s")
    start, notes = _start_window(ramped, ds.isel(time=slice(0, 2000)), 10.0, "si")  # 20 s: still growing
    assert start == 10.0 and "has not settled by t = 19.99 s" in notes[1]
    start, notes = _start_window(reference, ds, 10.0, "si")  # on bottom: the window stays
    assert start == 10.0 and len(notes) == 1


def test_study_summary_says_when_the_nominal_run_settles_after_the_window_starts():
    """A study keeps one window for every realization; after a ramped start whose nominal bit-speed
    oscillation settles later than it (or never), the summary's ``start`` says so, naming --transient."""
    from drillstring.stochastic.analysis import start_summary

    t = np.arange(0.0, 60.0, 0.01)

    def stats(start, speed):
        case = f'[initial]\nstart = "{start}"\nweight_ramp_time = 10.0\n[operation]\ntop_speed = {OMEGA}\n'
        return xr.Dataset({"bit_speed_nominal": ("time", speed)}, coords={"time": t}, attrs={"case": case})

    ramped = start_summary(stats("ramp", _growing_then_steady(t, 30.0)), 10.0)
    assert ramped["ramp_end"] == 10.0 and 30.0 - 2 * PERIOD <= ramped["settled"] <= 30.0
    assert f"settles at t = {ramped['settled']:.1f} s" in ramped["warning"]
    assert f"--transient {math.ceil(ramped['settled'])}" in ramped["warning"]
    assert start_summary(stats("ramp", _growing_then_steady(t, 30.0)), 35.0)["warning"] is None
    short = start_summary(stats("ramp", _growing_then_steady(t, 30.0)).isel(time=slice(0, 2500)), 10.0)
    assert short["settled"] is None and "has not settled by t = 24.99 s" in short["warning"]
    on_bottom = start_summary(stats("on_bottom", _growing_then_steady(t, 30.0)), 10.0)
    assert on_bottom["ramp_end"] == 0.0 and on_bottom["warning"] is None
