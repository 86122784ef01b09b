"""``drillstring estimate``: the shipped record's head through the command (files, JSON, scores against the
truth), the scores' arithmetic, and the errors of bad input."""

import json

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from drillstring.api.estimates import _scores, builtin_record
from drillstring.cli import app
from drillstring.estimation.surface import SurfaceRecord

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None,
        "DRILLSTRING_UNITS": None}


def _invoke(*args):
    return runner.invoke(app, [str(a) for a in args], env=_ENV)


@pytest.fixture(scope="module")
def short_record(tmp_path_factory):
    """The first 8 s of the shipped record (its header lines kept), and its truth file."""
    record, truth = builtin_record("stick_slip")
    lines = record.read_text(encoding="utf-8").splitlines()
    header = [i for i, line in enumerate(lines) if line.startswith("TIME")][0]
    rows = [line for line in lines[header + 1:] if float(line.split(",")[0]) <= 8.0]
    path = tmp_path_factory.mktemp("record") / "short.csv"
    path.write_text("\n".join(lines[:header + 1] + rows) + "\n", encoding="utf-8")
    return path, truth


def test_estimate_writes_its_files_and_scores_against_the_truth(short_record, tmp_path):
    record, truth = short_record
    out = tmp_path / "estimate"
    result = _invoke("estimate", "stick_slip", "--surface", record, "--truth", truth, "--out", out,
                     "--ensemble-size", 8, "--json")
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert payload["samples"] == 81 and payload["duration"] == pytest.approx(8.0)
    for name in ("dataset", "report"):
        assert (out / payload["files"][name].split("/")[-1]).is_file()
    assert {p.split("/")[-1] for p in payload["files"]["figures"]} == {"surface.png", "downhole.png"}
    with xr.open_dataset(out / "estimate.nc", engine="h5netcdf") as ds:
        assert ds["bit_speed"].attrs["units"] == "rad/s"
        assert ds["bit_speed_quantile"].shape == (81, 3)
        low, high = ds["bit_speed_quantile"].values[:, 0], ds["bit_speed_quantile"].values[:, 2]
        assert np.all(low <= high)
        assert ds["used_surface_torque"].values.sum() == 81 - 2  # the two empty cells at 2-2.1 s never used
    assert set(payload["scores"]) == {"bit_speed", "torque_on_bit"}
    assert 0.0 <= payload["scores"]["bit_speed"]["coverage_90"] <= 1.0
    assert payload["parameters"].keys() == {"a5", "weight_on_bit_bias"}


def test_scores_are_the_band_coverage_and_the_rmse():
    class Result:  # the two fields the scores read, written by hand
        time = np.array([0.0, 1.0, 2.0, 3.0])
        mean = {"bit_speed": np.array([10.0, 11.0, 12.0, 13.0])}
        quantiles = {"bit_speed": np.array([[9.0, 10.0, 11.0], [10.0, 11.0, 12.0], [11.0, 12.0, 13.0],
                                            [12.0, 13.0, 14.0]])}

        def coverage(self, name, truth):
            low, high = self.quantiles[name][:, 0], self.quantiles[name][:, 2]
            return float(np.mean((truth >= low) & (truth <= high)))

    truth = {"bit_speed": np.array([10.0, 13.0, 12.0, 16.0])}  # inside, outside, inside, outside
    record = SurfaceRecord.from_arrays([0.0, 1.0, 2.0, 3.0], top_speed=[10.0, 10.0, 10.0, 10.0])
    scores = _scores(Result(), record, truth)["bit_speed"]
    assert scores["coverage_90"] == 0.5
    assert scores["rmse"] == pytest.approx(np.sqrt((0 + 4 + 0 + 9) / 4))
    assert scores["surface_only_rmse"] == pytest.approx(np.sqrt((0 + 9 + 4 + 36) / 4))


def test_estimate_refuses_bad_input(tmp_path):
    result = _invoke("estimate", "reference", "--out", tmp_path / "e")
    assert result.exit_code == 2 and "ships none" in result.output
    result = _invoke("estimate", "stick_slip", "--surface", tmp_path / "missing.csv", "--out", tmp_path / "e")
    assert result.exit_code == 2 and "missing.csv" in result.output
    bad = tmp_path / "bad.csv"
    bad.write_text("TIME [s],RPM [rpm],STOR [kg]\n0,100,1\n1,100,1\n", encoding="utf-8")
    result = _invoke("estimate", "stick_slip", "--surface", bad, "--out", tmp_path / "e")
    assert result.exit_code == 2 and "STOR" in result.output and "kg" in result.output
    result = _invoke("estimate", "stick_slip", "--ensemble-size", 2, "--out", tmp_path / "e")
    assert result.exit_code == 2 and "estimator.ensemble_size = 2" in result.output


def test_help_states_the_estimators_default_ensemble_size():
    from drillstring.estimation.ensemble import EstimatorSettings

    result = _invoke("estimate", "--help")
    assert result.exit_code == 0
    assert f"else {EstimatorSettings().ensemble_size})" in " ".join(result.output.split())


@pytest.mark.parametrize("stop, code, words", [(ValueError, 1, "every member's forecast failed between t = "),
                                               (KeyboardInterrupt, 130, "interrupted after t = ")])
def test_a_run_stopped_early_writes_what_it_computed_and_says_where(short_record, tmp_path, monkeypatch, stop,
                                                                   code, words):
    """Every forecast failing, or Ctrl-C, after the spin-up and a few samples (4 members: 20 spin-up forecasts,
    then the record's): the files hold the samples before the stop, the message says where, the exit code is
    the run's failure (1) or the interruption's (130)."""
    from drillstring.estimation import ensemble

    real, calls = ensemble.advance, {"n": 0}

    def stopping(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] > 4 * (20 + 5):
            raise stop("made to stop by the test")
        return real(*args, **kwargs)

    monkeypatch.setattr(ensemble, "advance", stopping)
    record, truth = short_record
    out = tmp_path / "estimate"
    result = _invoke("estimate", "stick_slip", "--surface", record, "--truth", truth, "--out", out,
                     "--ensemble-size", 4)
    assert result.exit_code == code, result.output
    message = " ".join(result.output.split())
    assert words in message and f"(the estimate up to there is in {out})" in message
    with xr.open_dataset(out / "estimate.nc", engine="h5netcdf") as ds:
        assert 1 <= ds.sizes["time"] < 81 and words.split(" t = ")[0] in ds.attrs["stopped"]
    assert "stopped early" in (out / "report.html").read_text(encoding="utf-8")
