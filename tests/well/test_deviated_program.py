"""The whole program on a case with ``[well]`` (issue 34 item 4): a study, an operating map and a search of the
operating point run on the deviated case (coarse: a 60 m mesh and a small basis, so each run costs a fraction
of a second), their runs are the ``simulate`` and ``stability`` of the same case, and the study rebuilds every
realization (the parametric model does not cover a well) with one note saying so."""

import numpy as np
import pytest

import drillstring
from drillstring import api
from drillstring.case import load_case
from drillstring.dynamics.indicators import bit_area, cycle_metrics, steady_window
from drillstring.stochastic.montecarlo import nominal_weight_on_hook
from drillstring.well.stiff_string import case_stiff_string, case_well_buckling_margin
from drillstring.well.torque_drag import case_torque_drag

T_END = 0.5  # [s]
OUTPUT_STEP = 0.01  # [s]


@pytest.fixture(scope="module")
def deviated():
    """The deviated case on a 60 m mesh, 2 axial, 3 torsional and 2 lateral modes per plane."""
    case = load_case("deviated")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 60.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 2, "torsional_modes": 3,
                                                               "lateral_modes": 2})})


@pytest.fixture(scope="module")
def simulated(deviated):
    return api.simulate(deviated, t_end=T_END, output_step=OUTPUT_STEP)


def test_study_nominal_run_is_simulate_and_every_realization_is_rebuilt(deviated, simulated, tmp_path):
    """The study's nominal run (the deterministic run at the means) is ``simulate`` of the case to round-off;
    the parametric model refuses the well, so the study notes once that every realization is rebuilt, and the
    realizations differ from the nominal run (the weight-on-hook is random)."""
    notes = []
    outcome = api.monte_carlo_study(deviated, samples=2, t_end=T_END, output_step=OUTPUT_STEP, workers=1,
                                    out=tmp_path / "s", note=notes.append)
    rebuilt = [n for n in notes if "[well]" in n]
    assert len(rebuilt) == 1 and "every realization's reduced model is rebuilt" in rebuilt[0]
    stats = outcome.statistics
    np.testing.assert_allclose(stats.time.values, simulated.time.values, rtol=0, atol=1e-12)
    for name in ("bit_speed", "torque_on_bit", "force_on_bit", "rate_of_penetration"):
        nominal, run = stats[f"{name}_nominal"].values, simulated[name].values
        np.testing.assert_allclose(nominal, run, rtol=1e-9, atol=1e-9 * np.abs(run).max(), err_msg=name)
        assert np.abs(stats[f"{name}_mean"].values - run).max() > 1e-6 * np.abs(run).max(), name
    # the random weight-on-hook is the vertical one (weight − weight-on-bit), not the well's hook load
    summary = outcome.summary
    assert summary["weight_on_hook_mean"] == pytest.approx(deviated.weight - deviated.operation.weight_on_bit)
    assert summary["weight_on_hook_mean"] == nominal_weight_on_hook(deviated)
    assert summary["weight_on_hook_mean"] - case_stiff_string(deviated).hook_load > 1e5
    # its buckling margin is the well path's (sinusoidal), named as such, not the straight string's
    well = case_well_buckling_margin(deviated, case_stiff_string(deviated)).critical_weight_on_bit
    assert summary["buckling"]["critical_weight_on_bit"] == well and "well path" in summary["buckling"]["criterion"]


def test_map_point_is_simulate_and_its_root_is_stability(deviated, simulated, tmp_path):
    """A one-point map at the case's own top speed and weight-on-bit: its outputs are those of ``simulate``'s
    time histories (1e-9), its torsional and leading roots those of ``stability`` (1e-6)."""
    outcome = api.operating_map(deviated, top_speed=[deviated.operation.top_speed],
                                weight_on_bit=[deviated.operation.weight_on_bit], t_end=T_END,
                                output_step=OUTPUT_STEP, transient=0.2, workers=1, out=tmp_path / "m")
    point = outcome.dataset.isel(top_speed=0, weight_on_bit=0)
    well = case_well_buckling_margin(deviated, case_stiff_string(deviated)).critical_weight_on_bit
    assert outcome.dataset.attrs["critical_weight_on_bit"] == well  # the well path's buckling, not the straight's
    assert float(point["buckling_margin"]) == well - deviated.operation.weight_on_bit
    t = simulated.time.values
    obs = {name: simulated[name].values for name in simulated.data_vars}
    metrics = cycle_metrics(t, obs, deviated.operation.top_speed, bit_area(deviated), 0.2)
    for name in ("rate_of_penetration", "torque_on_bit", "force_on_bit"):
        assert float(point[f"mean_{name}"]) == pytest.approx(metrics[f"mean_{name}"], rel=1e-9), name
        steady = obs[name][steady_window(t, 0.2)]
        assert float(point[f"std_{name}"]) == pytest.approx(steady.std(), rel=1e-9, abs=1e-12), name
    found = api.stability(deviated)
    torsional = found.leading_by_family["torsional"]
    assert float(point["torsional_growth_rate"]) == pytest.approx(torsional.growth_rate, rel=1e-6)
    assert float(point["torsional_frequency"]) == pytest.approx(torsional.frequency, rel=1e-6)
    assert float(point["growth_rate"]) == pytest.approx(found.leading.growth_rate, rel=1e-6)
    assert float(point["steady_rate_of_penetration"]) == pytest.approx(found.steady_state.rate_of_penetration,
                                                                       rel=1e-6)


def test_optimize_runs_on_a_two_by_two_design(deviated, tmp_path):
    """A search over top speed × weight-on-bit, its initial design of 4 points alone, 2 realizations each:
    every realization finishes and the recommended point is one of the design."""
    outcome = drillstring.optimize(deviated, variables={"top_speed": "100 rpm:140 rpm", "weight_on_bit": "60 kN:90 kN"},
                           samples=2, points=4, initial=4, t_end=T_END, output_step=0.05, sigma=5e3, workers=1,
                           out=tmp_path)
    summary = outcome.summary
    assert summary["realizations"] == 8 and not summary["failures"]
    assert len(summary["design"]) == 4
    assert summary["recommended"]["values"] in summary["design"]
    assert np.all(np.isfinite(outcome.dataset.mean_rate_of_penetration.values))


@pytest.mark.parametrize("law, operation", [("off_bottom", "rotating_off_bottom"), ("tucker_wang", "drilling")])
def test_hook_load_in_time_is_the_stiff_strings_and_the_soft_strings(law, operation):
    """The ``hook_load`` channel (the top axially free under a prescribed force: the static hook load plus the
    weight not yet transferred during the start's ramp) on the case's own 10 m mesh: after the ramp it is the
    stiff string's static hook load exactly, and the soft string's torque-and-drag hook load of the same
    operation to 2e-5 (frictionless both: without friction the weight's component along the path)."""
    case = load_case("deviated")
    case = case.model_copy(update={
        "bit_rock": case.bit_rock.model_copy(update={"law": law}),
        "initial": case.initial.model_copy(update={"weight_ramp_time": 0.1}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 2, "torsional_modes": 2,
                                                               "lateral_modes": 1})})
    run = api.simulate(case, t_end=0.2, output_step=0.05)
    after = run.time.values >= 0.1
    stiff = case_stiff_string(case).hook_load  # the case's weight on bit: 0 off bottom
    np.testing.assert_array_equal(run.hook_load.values[after], stiff)
    soft = case_torque_drag(case)[operation].hook_load
    assert stiff == pytest.approx(soft, rel=2e-5)
    assert abs(stiff - soft) > 1.0  # not the same computation: the stiff string's bending and nodes (−9 N)
    # during the ramp the hook holds the weight not yet on the bit (none off bottom)
    w = case.operation.weight_on_bit if law != "off_bottom" else 0.0
    np.testing.assert_allclose(run.hook_load.values[0], stiff + w, rtol=1e-15)


def test_figure_of_the_string_in_the_well(deviated, tmp_path):
    """The figure of the stiff string in its well: a 3-D path and the contact force per node; the nodes on the
    wall are drawn with their forces, the free ones apart, in the unit system asked for."""
    from drillstring.outputs.torque_drag_plots import (
        plot_string_in_well,
        string_in_well_figure,
    )

    state = case_stiff_string(deviated)
    fig = string_in_well_figure(state)
    path3d = fig.axes[0]
    assert path3d.name == "3d"
    drawn = path3d.collections[0].get_array()  # the nodes on the wall, coloured by their force [kN]
    np.testing.assert_allclose(np.sort(drawn), np.sort(state.side_force[state.in_contact]) / 1e3, rtol=1e-12)
    assert 0 < drawn.size < state.side_force.size
    assert f"{state.hook_load / 1e3:,.2f} kN" in fig.get_suptitle()
    field = string_in_well_figure(state, units="field")
    assert "klbf" in field.get_suptitle() and "[ft]" in field.axes[1].get_ylabel()
    png = plot_string_in_well(state, tmp_path / "well.png")
    assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size > 20_000


def test_simulate_command_writes_the_well_figure(deviated, tmp_path):
    """``drillstring simulate --plot F.png`` on a case with ``[well]`` writes ``F-well.png`` too (and says
    so); a case without ``[well]`` does not."""
    import json

    from typer.testing import CliRunner

    from drillstring.cli import app

    case_file = tmp_path / "deviated.toml"
    case_file.write_text(deviated.to_toml(), encoding="utf-8")
    png = tmp_path / "run.png"
    result = CliRunner().invoke(app, ["simulate", str(case_file), "--t-end", "0.1", "--out", str(tmp_path / "run.nc"),
                                      "--plot", str(png), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    well = tmp_path / "run-well.png"
    assert data["well_figure"] == str(well) and well.read_bytes().startswith(b"\x89PNG")
    vertical = tmp_path / "vertical.toml"
    vertical.write_text(deviated.model_copy(update={"well": None}).to_toml(),
                        encoding="utf-8")
    result = CliRunner().invoke(app, ["simulate", str(vertical), "--t-end", "0.1", "--out",
                                      str(tmp_path / "v.nc"), "--plot", str(tmp_path / "v.png"), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["well_figure"] is None and not (tmp_path / "v-well.png").exists()
