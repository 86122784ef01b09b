"""Figures: every plotting function writes a PNG from small synthetic Datasets (no simulation), and the
figure it draws holds the data it was given: the curves (in display units), the panels, labels and titles
(read back from the Matplotlib figure before it is saved)."""

import math

import numpy as np
import pytest
import xarray as xr

from drillstring import plots
from drillstring.outputs import canvas

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
TOP_SPEED = 100.0 * 2.0 * math.pi / 60.0  # rad/s


def _assert_png(path):
    assert path.exists()
    data = path.read_bytes()
    assert data.startswith(PNG_SIGNATURE)
    assert len(data) > 5_000  # axes, curves and labels, not an empty canvas


@pytest.fixture
def drawn(monkeypatch):
    """The figures the plotting functions save, in order (each still written to its file)."""
    figures = []
    save = canvas.save_png

    def keep(fig, path):
        figures.append(fig)
        return save(fig, path)

    monkeypatch.setattr(canvas, "save_png", keep)
    return figures


def _lines(ax):
    """(x, y) of each plotted line of ``ax`` (reference lines of axhline included)."""
    return [(np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float))
            for line in ax.get_lines()]


@pytest.fixture
def run_dataset():
    """One run in the layout of drillstring.results.run_dataset, two probes."""
    t = np.linspace(0.0, 5.0, 101)
    radial = np.stack([1e-3 * np.abs(np.sin(t)), 2e-3 * np.abs(np.cos(t))], axis=1)
    return xr.Dataset(
        {
            "rate_of_penetration": ("time", 3.5e-3 * (1 - np.exp(-t))),
            "bit_speed": ("time", TOP_SPEED * (1 + 0.3 * np.exp(-t) * np.sin(3 * t))),
            "torque_on_bit": ("time", 4.5e3 * (1 - 0.5 * np.exp(-t))),
            "force_on_bit": ("time", 1e5 * np.ones_like(t)),
            "radial_displacement": (("time", "probe"), radial),
            "lateral_displacement": (("time", "probe", "direction"),
                                     np.stack([radial * np.cos(TOP_SPEED * t)[:, None],
                                               radial * np.sin(TOP_SPEED * t)[:, None]], axis=-1)),
            "contact_force": ("time", 1e4 * np.clip(np.sin(7 * t), 0, None)),
        },
        coords={"time": t, "x": ("probe", [1500.0, 1560.0]), "gap": ("probe", [0.0357, 0.0357])},
        attrs={"top_speed": TOP_SPEED, "status": "success", "case": 'name = "synthetic"\n', "impacts": 5},
    )


@pytest.fixture
def stats_dataset():
    """Study statistics in the layout of drillstring.stochastic.analysis.study_statistics."""
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 4.0, 81)
    scales = {"rate_of_penetration": 3.5e-3, "bit_speed": TOP_SPEED, "torque_on_bit": 4.5e3,
              "force_on_bit": 1e5}
    data = {}
    n_s = 8
    for name, scale in scales.items():
        samples = scale * (1 + 0.05 * rng.standard_normal((n_s, 1))) * (1 + 0.1 * np.sin(t))
        mean = samples.mean(axis=0)
        std = samples.std(axis=0, ddof=1)
        data[f"{name}_mean"] = ("time", mean)
        data[f"{name}_std"] = ("time", std)
        data[f"{name}_lower"] = ("time", np.quantile(samples, 0.025, axis=0))
        data[f"{name}_upper"] = ("time", np.quantile(samples, 0.975, axis=0))
        data[f"{name}_dispersion"] = ("time", std / np.abs(mean))
        data[f"{name}_nominal"] = ("time", scale * (1 + 0.1 * np.sin(t)))
        energy = np.trapezoid(samples**2, t, axis=1)
        data[f"{name}_convergence"] = ("n_samples", np.cumsum(energy) / np.arange(1, n_s + 1))
    return xr.Dataset(
        data,
        coords={"time": t, "n_samples": np.arange(1, n_s + 1)},
        attrs={"n_samples": n_s, "sigma": 5000.0, "level": 0.95, "weight_on_hook_dispersion": 0.0047,
               "weight_on_bit_dispersion": 0.05},
    )


def test_plot_run_writes_png(run_dataset, tmp_path, drawn):
    path = plots.plot_run(run_dataset, tmp_path / "sub" / "run.png", probe_x=1560.0)
    assert path == tmp_path / "sub" / "run.png"
    _assert_png(path)
    (fig,) = drawn
    rop, speed, radial, tob, orbit, contact = fig.axes
    t = run_dataset.time.values
    (x, y), = _lines(rop)  # ROP in m/h
    np.testing.assert_allclose(x, t)
    np.testing.assert_allclose(y, 3600 * run_dataset.rate_of_penetration.values)
    (_, bit), (_, top) = _lines(speed)  # bit speed and the imposed top speed, in rpm
    np.testing.assert_allclose(bit, run_dataset.bit_speed.values * 60 / (2 * math.pi))
    np.testing.assert_allclose(top, 100.0)
    assert radial.get_title() == "probe at x = 1560 m"
    (_, r), (_, gap) = _lines(radial)  # the probe's radial displacement and its gap, in mm
    np.testing.assert_allclose(r, 1e3 * run_dataset.radial_displacement.isel(probe=1).values)
    np.testing.assert_allclose(gap, 35.7)
    np.testing.assert_allclose(_lines(tob)[0][1], run_dataset.torque_on_bit.values / 1e3)  # kN·m
    assert "rate of penetration" in rop.get_ylabel().lower() and "[m/h]" in rop.get_ylabel()
    assert fig._suptitle.get_text() == "Drilling run: case 'synthetic'"


def test_plot_run_panels_fit_the_case(run_dataset, tmp_path, drawn):
    """A torsional-axial case with a Detournay bit, a top drive and a ramped start (issue 25): no lateral
    panels (radial displacement, orbit, contact force), but the quill speed, the surface torque, the force on
    bit with its wear-flat part, the depth of cut and the hook load."""
    t = run_dataset.time.values
    ds = run_dataset.drop_vars(["radial_displacement", "lateral_displacement", "contact_force"]).assign(
        quill_speed=("time", TOP_SPEED * (1 + 0.1 * np.sin(t))),
        surface_torque=("time", 5e3 + 1e3 * np.sin(t)),
        wear_flat_force=("time", 6e4 * np.ones_like(t)),
        depth_of_cut=("time", 4e-3 * np.sin(t)),
        hook_load=("time", 5e5 + 1e5 * (1 - np.minimum(t / 2.0, 1.0))),
    ).assign_attrs(lateral_modes=0, top_drive="pi")
    assert plots.run_panels(ds) == ("rop", "speed", "torque", "force", "depth_of_cut", "hook_load")
    assert plots.run_panels(run_dataset) == ("rop", "speed", "radial", "torque", "orbit", "contact")
    _assert_png(plots.plot_run(ds, tmp_path / "detournay.png"))
    (fig,) = drawn
    rop, speed, torque, force, depth, hook = fig.axes
    (_, bit), (_, quill), (_, set_point) = _lines(speed)
    np.testing.assert_allclose(quill, ds.quill_speed.values * 60 / (2 * math.pi))
    np.testing.assert_allclose(_lines(torque)[1][1], ds.surface_torque.values / 1e3)
    (_, fob), (_, wear) = _lines(force)
    np.testing.assert_allclose(fob, 100.0) and np.testing.assert_allclose(wear, 60.0)  # kN
    np.testing.assert_allclose(_lines(depth)[0][1], 1e3 * ds.depth_of_cut.values)  # mm
    np.testing.assert_allclose(_lines(hook)[0][1], ds.hook_load.values / 1e3)
    assert "hook load [kN]" == hook.get_ylabel() and "depth of cut [mm]" == depth.get_ylabel()


def test_plot_run_partial_failed_run(run_dataset, tmp_path, drawn):
    partial = run_dataset.isel(time=slice(0, 10)).assign_attrs(status="failed")
    _assert_png(plots.plot_run(partial, tmp_path / "partial.png"))
    (fig,) = drawn
    assert fig._suptitle.get_text() == "Drilling run: case 'synthetic' (failed, stopped at t = 0.45 s)"
    assert len(_lines(fig.axes[0])[0][1]) == 10  # plotted as far as it went


def test_plot_run_differs_with_the_probe(run_dataset, tmp_path, drawn):
    plots.plot_run(run_dataset, tmp_path / "a.png", probe_x=1490.0)
    plots.plot_run(run_dataset, tmp_path / "b.png", probe_x=1570.0)
    first, second = (fig.axes[2] for fig in drawn)
    assert (first.get_title(), second.get_title()) == ("probe at x = 1500 m", "probe at x = 1560 m")
    np.testing.assert_allclose(_lines(first)[0][1], 1e3 * run_dataset.radial_displacement.isel(probe=0).values)
    np.testing.assert_allclose(_lines(second)[0][1], 1e3 * run_dataset.radial_displacement.isel(probe=1).values)


def test_plot_convergence_writes_png(stats_dataset, tmp_path, drawn):
    """conv(n_s) of each observable divided by its last value: four curves ending at 1, and the line at 1."""
    _assert_png(plots.plot_convergence(stats_dataset, tmp_path / "convergence.png"))
    (ax,) = drawn[0].axes
    *curves, (_, one) = _lines(ax)
    assert len(curves) == len(OBSERVABLES)
    np.testing.assert_allclose(one, 1.0)
    for (n, y), name in zip(curves, OBSERVABLES):
        conv = stats_dataset[f"{name}_convergence"].values
        np.testing.assert_array_equal(n, np.arange(1, 9))
        np.testing.assert_allclose(y, conv / conv[-1])
        assert y[-1] == 1.0
def test_plot_convergence_needs_convergence_variables(stats_dataset, tmp_path):
    bare = stats_dataset.drop_vars([f"{v}_convergence" for v in OBSERVABLES])
    with pytest.raises(ValueError, match="convergence"):
        plots.plot_convergence(bare, tmp_path / "none.png")


def test_plot_envelopes_writes_png(stats_dataset, tmp_path, drawn):
    """One panel per observable: the 95 % envelope between lower and upper, the mean and the nominal run."""
    _assert_png(plots.plot_envelopes(stats_dataset, tmp_path / "envelopes.png"))
    axes = drawn[0].axes
    assert len(axes) == 4
    for ax, name, factor in zip(axes, OBSERVABLES, (3600.0, 60 / (2 * math.pi), 1e-3, 1e-3)):
        (_, mean), (_, nominal) = _lines(ax)
        np.testing.assert_allclose(mean, factor * stats_dataset[f"{name}_mean"].values)
        np.testing.assert_allclose(nominal, factor * stats_dataset[f"{name}_nominal"].values)
        (band,) = ax.collections  # the envelope's polygon spans exactly lower..upper
        y = band.get_paths()[0].vertices[:, 1]
        assert y.min() == pytest.approx(factor * stats_dataset[f"{name}_lower"].values.min())
        assert y.max() == pytest.approx(factor * stats_dataset[f"{name}_upper"].values.max())
    assert [t.get_text() for t in axes[0].get_legend().get_texts()] == ["95% envelope", "mean", "nominal"]


def test_plot_dispersion_writes_png(stats_dataset, tmp_path, drawn):
    """Dispersion in % of each observable vs time, the transient t < 1 s shaded."""
    _assert_png(plots.plot_dispersion(stats_dataset, tmp_path / "dispersion.png", t_transient=1.0))
    axes = drawn[0].axes
    assert len(axes) == 4
    for ax, name in zip(axes, OBSERVABLES):
        (t, y), = _lines(ax)
        np.testing.assert_allclose(y, 100 * stats_dataset[f"{name}_dispersion"].values)
        (shade,) = ax.patches
        x = shade.get_patch_transform().transform(shade.get_path().vertices)[:, 0]  # Rectangle or Polygon
        assert (x.min(), x.max()) == pytest.approx((0.0, 1.0))
    assert drawn[0]._suptitle.get_text() == "Dispersion of the response, n_s = 8, σ_WOH = 5 kN\nδ_WOB = 5 %"


def test_plot_realizations_one_histogram_per_metric(stats_dataset, tmp_path):
    from drillstring.quantities import METRIC_DISPLAY

    with pytest.raises(ValueError, match="realization_"):
        plots.plot_realizations(stats_dataset, tmp_path / "none.png")
    stats = stats_dataset.copy()
    n_s = 8
    for name in METRIC_DISPLAY:
        stats[f"realization_{name}"] = xr.DataArray(np.linspace(1.0, 2.0, n_s), dims="realization",
                                                     attrs={"nominal": 1.5})
    stats["realization_period"] = xr.DataArray(np.full(n_s, np.nan), dims="realization")  # never oscillates
    _assert_png(plots.plot_realizations(stats, tmp_path / "realizations.png"))
    figures = plots.plot_study(stats, tmp_path / "out", t_transient=1.0)
    assert set(figures) == {"convergence", "envelopes", "dispersion", "realizations"}


def test_plot_study_writes_the_three_figures(stats_dataset, tmp_path):
    figures = plots.plot_study(stats_dataset, tmp_path / "out", t_transient=1.0)
    assert set(figures) == {"convergence", "envelopes", "dispersion"}
    for name, path in figures.items():
        assert path == tmp_path / "out" / f"{name}.png"
        _assert_png(path)


def test_no_global_pyplot_state(stats_dataset, tmp_path):
    """Figures are drawn without pyplot: nothing stays open in a notebook or a worker."""
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    plots.plot_study(stats_dataset, tmp_path, t_transient=1.0)
    assert plt.get_fignums() == before


def test_plot_compare_writes_png(run_dataset, tmp_path, drawn):
    reduced = run_dataset.copy(deep=True)
    reduced["bit_speed"] = reduced["bit_speed"] * 1.01
    path = plots.plot_compare(run_dataset, reduced, tmp_path / "sub" / "compare.png", probe_x=1560.0)
    assert path == tmp_path / "sub" / "compare.png"
    _assert_png(path)
    speed = drawn[0].axes[1]  # case 1 solid, case 2 dashed, each its own bit speed
    full, dashed = (line for line in speed.get_lines() if line.get_label().startswith("case"))
    assert (full.get_linestyle(), dashed.get_linestyle()) == ("-", "--")
    assert full.get_label() == "case 1 (full)" and dashed.get_label() == "case 2 (bit–rock + contact)"
    np.testing.assert_allclose(full.get_ydata(), run_dataset.bit_speed.values * 60 / (2 * math.pi))
    np.testing.assert_allclose(dashed.get_ydata(), 1.01 * run_dataset.bit_speed.values * 60 / (2 * math.pi))
    # a partial (failed) run and a dataset without probes still plot
    partial = reduced.isel(time=slice(0, 10)).assign_attrs(status="failed")
    bare = run_dataset.drop_vars(["radial_displacement", "x", "gap"])
    _assert_png(plots.plot_compare(bare, partial.drop_vars(["radial_displacement", "x", "gap"]),
                                   tmp_path / "partial.png"))


def test_figures_follow_the_unit_system(run_dataset, monkeypatch, tmp_path):
    """The axes of a run figure in field units: klbf, kft·lbf, ft/h, in; the plotted numbers are the SI ones
    times the display factor (the torque over 1 kft·lbf = 1355.8179483314004 N·m)."""
    drawn = {}

    def keep(fig, path):
        drawn[str(path)] = fig
        return path

    monkeypatch.setattr(canvas, "save_png", keep)
    plots.plot_run(run_dataset, tmp_path / "si.png", units="si")
    plots.plot_run(run_dataset, tmp_path / "field.png", units="field")
    si, field = ([ax.get_ylabel() for ax in drawn[str(tmp_path / f)].axes] for f in ("si.png", "field.png"))
    # the torque panel holds the torque-on-bit (its first curve) and the surface torque
    assert "rate of penetration [m/h]" in si and "torque [kN·m]" in si and "contact force [kN]" in si
    assert "rate of penetration [ft/h]" in field and "torque [kft·lbf]" in field
    assert "radial displacement [in]" in field and "contact force [klbf]" in field
    tob_si = drawn[str(tmp_path / "si.png")].axes[3].lines[0].get_ydata()
    tob_field = drawn[str(tmp_path / "field.png")].axes[3].lines[0].get_ydata()
    np.testing.assert_allclose(tob_field * 1355.8179483314004, tob_si * 1e3, rtol=1e-12)


@pytest.mark.parametrize("name", ["Well $A", "Well $A$ and $\\\\frac{1}{$"])
def test_case_names_are_plain_text_in_figures(run_dataset, tmp_path, name):
    """A case name is drawn as written: dollar signs never start Matplotlib's mathtext."""
    ds = run_dataset.assign_attrs(case=f'name = "{name}"\n')
    assert canvas.case_name(ds.attrs["case"]).replace("\\$", "$") == name.replace("\\\\", "\\")
    _assert_png(plots.plot_run(ds, tmp_path / "run.png"))
    _assert_png(plots.plot_compare(ds, ds, tmp_path / "compare.png"))


KLBF, FT, PSI = 4448.2216152605, 0.3048, 6894.757293168361  # N, m, Pa (NIST)


def test_realization_histograms_follow_the_unit_system(stats_dataset, tmp_path, drawn):
    """realizations.png in field units: ROP in ft/h, TOB in kft·lbf, FOB in klbf, MSE in psi, bit speed in rpm;
    each histogram's mean line is the SI mean over the defining factor."""
    stats = stats_dataset.copy()
    si_values = {"mean_rate_of_penetration": 3.5e-3, "mean_torque_on_bit": 4.5e3, "mean_force_on_bit": 1e5,
                 "mechanical_specific_energy": 2e8, "bit_speed_min": 5.0}
    for name, value in si_values.items():
        stats[f"realization_{name}"] = xr.DataArray(value * np.linspace(0.9, 1.1, 8), dims="realization",
                                                     attrs={"nominal": value})
    plots.plot_realizations(stats, tmp_path / "field.png", units="field")
    axes = {ax.get_xlabel(): ax for ax in drawn[0].axes if ax.get_visible()}
    expected = {"ROP mean [ft/h]": 3.5e-3 * 3600 / FT, "TOB mean [kft·lbf]": 4.5e3 / (KLBF * FT),
                "FOB mean [klbf]": 1e5 / KLBF, "MSE [psi]": 2e8 / PSI, "bit speed min [rpm]": 5.0 * 30 / math.pi}
    assert set(axes) == set(expected)
    for label, value in expected.items():
        mean, nominal = (x[0] for x, _ in _lines(axes[label]))
        assert mean == pytest.approx(value) and nominal == pytest.approx(value)
    assert "σ_WOH = 1.124 klbf" in drawn[0]._suptitle.get_text()  # 5 kN


@pytest.fixture
def sampled_map():
    """A probabilistic map in the layout of drillstring.stochastic.probabilistic_map.sampled_map_dataset."""
    speeds, weights = np.array([80.0, 160.0]) * math.pi / 30, np.array([6e4, 9e4])
    quantiles = np.array([0.025, 0.5, 0.975])
    grid = np.array([[0.1, 0.4], [0.2, 0.9]])
    data = {name: (("top_speed", "weight_on_bit"), grid) for name, _ in plots.PROBABILITY_PANELS}
    rop = 1e-3 * np.arange(1.0, 13.0).reshape(2, 2, 3)
    data["rate_of_penetration_q"] = (("top_speed", "weight_on_bit", "quantile"), rop)
    data["stick_slip_index_q"] = (("top_speed", "weight_on_bit", "quantile"), rop * 100)
    return xr.Dataset(data, coords={"top_speed": speeds, "weight_on_bit": weights, "quantile": quantiles},
                      attrs={"samples": 3, "t_end": 1.0, "t_transient": 0.5, "critical_weight_on_bit": 8e4})


@pytest.mark.parametrize("units, force, rop", [("si", (1e3, "kN"), (1 / 3600, "m/h")),
                                               ("field", (KLBF, "klbf"), (FT / 3600, "ft/h"))])
def test_probability_and_quantile_maps_follow_the_unit_system(sampled_map, tmp_path, drawn, units, force, rop):
    """probabilities.png and quantiles.png: weights-on-bit, the buckling limit and the ROP quantiles in the unit
    system's units (the SI values over the defining factors)."""
    _assert_png(plots.plot_probability_map(sampled_map, tmp_path / "p.png", units=units))
    _assert_png(plots.plot_quantile_map(sampled_map, tmp_path / "q.png", units=units))
    (factor, label), (rop_factor, rop_label) = force, rop
    for fig in drawn:
        ax = fig.axes[0]
        assert ax.get_ylabel() == f"weight-on-bit [{label}]"
        (x, y), = [line for line in _lines(ax) if len(line[0]) == 2 and line[1][0] == line[1][1]]  # buckling
        assert y[0] == pytest.approx(8e4 / factor)
        assert ax.get_ylim() == pytest.approx((6e4 / factor, 9e4 / factor))  # the filled contours span the grid
        legend = fig.legends[0].get_texts()[0].get_text()
        assert legend == f"lateral buckling of the nominal string, WOB = {8e4 / factor:.4g} {label}"
    colorbars = [ax.get_ylabel() for ax in drawn[1].axes if ax.get_label() == "<colorbar>"]
    assert colorbars[0] == f"mean ROP [{rop_label}]"
    levels = drawn[1].axes[0].collections[0].levels  # the 2.5 % ROP quantile panel: its first and last band
    low, high = 1e-3 / rop_factor, 10e-3 / rop_factor  # hold the smallest and largest values
    assert levels[0] <= low <= levels[1] and levels[-2] <= high <= levels[-1]


def test_plot_run_shows_a_downhole_motor(run_dataset, tmp_path, drawn):
    """A case with a downhole motor (issue 38): a panel of its speed, its torque beside the torque on bit,
    and a panel of its differential pressure, each in the unit system's unit (field: rpm, kft·lbf, psi)."""
    t = run_dataset.time.values
    ds = run_dataset.assign(motor_speed=("time", 7.0 + np.sin(t)), motor_torque=("time", 6e3 + 1e3 * np.cos(t)),
                            differential_pressure=("time", 3e6 + 1e5 * np.sin(t)))
    assert plots.run_panels(ds)[-2:] == ("motor_speed", "motor_pressure")
    assert "motor_speed" not in plots.run_panels(run_dataset)
    _assert_png(plots.plot_run(ds, tmp_path / "motor.png", units="field"))
    (fig,) = drawn
    axes = fig.axes
    torque, motor_speed, pressure = axes[3], axes[6], axes[7]
    np.testing.assert_allclose(_lines(torque)[-1][1], ds.motor_torque.values / 1355.8179483314004, rtol=1e-9)
    np.testing.assert_allclose(_lines(motor_speed)[0][1], ds.motor_speed.values * 60 / (2 * math.pi))
    np.testing.assert_allclose(_lines(pressure)[0][1], ds.differential_pressure.values / 6894.757293168361,
                               rtol=1e-9)
    assert "[rpm]" in motor_speed.get_ylabel() and "[psi]" in pressure.get_ylabel()
