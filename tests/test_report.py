"""HTML report: self-contained (inline CSS, base64 figures, no external resource), escaped, with the table."""

import base64
import re

import pytest

from drillstring.case import load_case
from drillstring.report import write_report

# A 1x1 PNG.
PNG = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="
)


def _entry(mean, maximum, d_woh=0.0047, d_wob=0.05):
    return {
        "dispersion_time_mean": mean,
        "dispersion_max": maximum,
        "time_of_max": 12.5,
        "ratio_time_mean": {"weight_on_hook": mean / d_woh, "weight_on_bit": mean / d_wob},
        "ratio_max": {"weight_on_hook": maximum / d_woh, "weight_on_bit": maximum / d_wob},
    }


@pytest.fixture
def summary():
    return {
        "n_samples": 47,
        "n_failed": 3,
        "seed": 11,
        "sigma": 5000.0,
        "weight_on_hook_mean": 1.0634e6,
        "weight_on_hook_dispersion": 0.0047,
        "weight_on_bit_dispersion": 0.05,
        "t_transient": 10.0,
        "observables": {
            "rate_of_penetration": _entry(0.0692, 0.0713),
            "bit_speed": _entry(0.00209, 0.00848),
            "torque_on_bit": _entry(0.0469, 0.0506),
            "force_on_bit": _entry(0.0448, 0.0451),
        },
        "convergence_change_second_half": {"rate_of_penetration": 0.023},
    }


@pytest.fixture
def report(tmp_path, summary):
    figures = {}
    for name in ("envelopes", "dispersion"):
        path = tmp_path / f"{name}.png"
        path.write_bytes(PNG)
        figures[f"{name} <figure>"] = path
    path = write_report(
        tmp_path / "out" / "report.html",
        title="Study <of> 'reference' & co",
        case_toml=load_case("reference").to_toml(),
        summary=summary,
        figures=figures,
        run_info={"wall time [s]": 123.4, "workers": 2,
                  "failures": {"4": "SimulationError: step size <collapsed> at t = 3 s"}},
    )
    return path, path.read_text(encoding="utf-8")


def test_report_written(report, tmp_path):
    path, text = report
    assert path == tmp_path / "out" / "report.html"
    assert text.startswith("<!DOCTYPE html>")
    assert text.rstrip().endswith("</html>")


def _key_values(text: str) -> dict[str, str]:
    """The two-column tables of the report: label -> value cell, exactly."""
    return dict(re.findall(r"<tr><th>([^<]*)</th><td>(.*?)</td></tr>", text))


def _observable_rows(text: str) -> dict[str, dict[str, str]]:
    """The dispersion table: observable -> {column header: cell}, exactly."""
    table = text[text.index("<th>observable</th>"):]
    headers = re.findall(r"<th>([^<]*)</th>", table[: table.index("</tr>")])[1:]
    rows = {}
    for label, cells in re.findall(r"<tr><td>([^<]*)</td>((?:<td class=\"num\">[^<]*</td>)+)</tr>", text):
        rows[label] = dict(zip(headers, re.findall(r'<td class="num">([^<]*)</td>', cells), strict=True))
    return rows


def test_report_has_the_table_values(report):
    """Each number in the cell of its own row and column (not just somewhere in the page)."""
    _, text = report
    kv = _key_values(text)
    assert kv["realizations used (n_s)"] == "47"
    assert kv["failed realizations"] == "3"
    assert kv["seed"] == "11"
    assert kv["σ of the weight-on-hook"] == "5 kN"
    assert kv["mean weight-on-hook"] == "1063.4 kN"
    assert kv["weight-on-hook dispersion δ_WOH"] == "0.47 %"
    assert kv["weight-on-bit dispersion δ_WOB"] == "5 %"
    assert kv["summaries over"] == "t ≥ 10 s"
    assert kv["wall time [s]"] == "123.4"
    assert kv["workers"] == "2"
    rows = _observable_rows(text)
    assert list(rows) == ["rate of penetration", "bit speed", "torque-on-bit", "force-on-bit"]
    rop = rows["rate of penetration"]
    assert rop["time-mean δ [%]"] == "6.92" and rop["max δ [%]"] == "7.13"
    assert rop["time of max [s]"] == "12.5"
    assert rop["mean δ / δ_WOH"] == "14.7" and rop["mean δ / δ_WOB"] == "1.38"
    assert rop["conv(n_s) change, 2nd half [%]"] == "2.3"
    for label, mean, maximum in (("bit speed", "0.209", "0.848"), ("torque-on-bit", "4.69", "5.06"),
                                 ("force-on-bit", "4.48", "4.51")):
        assert (rows[label]["time-mean δ [%]"], rows[label]["max δ [%]"]) == (mean, maximum), label


def test_report_has_the_case(report):
    _, text = report
    assert "<details>" in text and "[bit_rock]" in text  # full TOML, collapsible
    assert "100 rpm" in text and "100 kN" in text and "1600 m" in text  # key numbers, display units


def test_report_embeds_figures(report):
    _, text = report
    assert text.count('src="data:image/png;base64,') == 2
    assert base64.b64encode(PNG).decode() in text


def test_report_is_self_contained(report):
    _, text = report
    assert "http" not in text  # no link, script, stylesheet or font from elsewhere
    assert "<script" not in text
    assert not re.search(r'<link\b', text)
    assert not re.search(r'src="(?!data:)', text)
    assert "<style>" in text


def test_report_escapes_text(report):
    _, text = report
    assert "Study &lt;of&gt; &#x27;reference&#x27; &amp; co" in text
    assert "<of>" not in text
    assert "step size &lt;collapsed&gt;" in text
    assert "envelopes &lt;figure&gt;" in text


def test_report_tolerates_missing_pieces(tmp_path):
    path = write_report(tmp_path / "r.html", title="t", case_toml="not = [valid toml", summary={},
                        figures={}, run_info={})
    text = path.read_text(encoding="utf-8")
    assert "not = [valid toml" in text
    assert "http" not in text


def test_report_in_field_units(tmp_path, summary):
    """The case table and the study rows in field units: the SI numbers over the defining factors."""
    path = write_report(tmp_path / "report.html", title="field", case_toml=load_case("reference").to_toml(),
                        summary=summary, figures={}, run_info={}, units="field")
    text = path.read_text(encoding="utf-8")
    klbf, ft, inch, ppg = 4448.2216152605, 0.3048, 0.0254, 119.826427
    assert f"{100e3 / klbf:.4g} klbf" in text  # weight-on-bit, 22.48
    assert f"{1600 / ft:.6g} ft" in text  # string length, 5249.34
    assert f"{0.3 / inch:.4g} in" in text  # borehole, 11.81
    assert f"{1200 / ppg:.4g} ppg" in text  # mud, 10.01
    assert f"{5000 / klbf:.4g} klbf" in text  # σ of the weight-on-hook, 1.124
    assert "100 kN</td>" not in text and "1600 m</td>" not in text  # no SI row left
