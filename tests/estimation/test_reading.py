"""Reading a surface record (drillstring.estimation.reading): columns by mnemonic or by the caller, units from
the header or given, converted to SI against constants written here, times as numbers or timestamps, and the
refusals (a unit of the wrong dimension, a missing unit, times that do not increase, no time column)."""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest

from drillstring.estimation.reading import MNEMONICS, read_surface_record
from drillstring.estimation.surface import CHANNELS, MISSING, USABLE

# Independent conversion constants (exact definitions): the pound-force, the foot, the psi, the revolution.
LBF = 0.45359237 * 9.80665  # N
FOOT = 0.3048  # m
PSI = LBF / (0.0254**2)  # Pa
RPM = 2.0 * math.pi / 60.0  # rad/s


def _write(tmp_path, text, name="record.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _rows(n=40, step=0.1, seed=0):
    """Smooth, noisy channel values in their file units (rpm, kN*m, kN, m, MPa)."""
    rng = np.random.default_rng(seed)
    t = step * np.arange(n)
    return t, {
        "rpm": 100.0 + 0.3 * rng.standard_normal(n),
        "torque": 6.0 + 0.5 * np.sin(t) + 0.05 * rng.standard_normal(n),
        "hook": 1664.0 + rng.standard_normal(n),
        "block": 25.0 - 0.003 * t + 0.002 * rng.standard_normal(n),
        "spp": 20.0 + 0.05 * rng.standard_normal(n),
    }


def _csv(header, t, columns, fmt="{:.6f}"):
    lines = [header] + [",".join([f"{t[k]:.3f}"] + [fmt.format(c[k]) for c in columns]) for k in range(len(t))]
    return "\n".join(lines) + "\n"


def test_mnemonics_map_every_channel_case_insensitively(tmp_path):
    t, v = _rows()
    header = "Time [s],surf-rpm [rpm],Surf Torque [kN*m],hookload [kN],blkpos [m],spp [MPa]"
    record = read_surface_record(_write(tmp_path, _csv(header, t, list(v.values()))))
    assert set(record.channels) == set(CHANNELS)
    np.testing.assert_allclose(record.time, t, atol=1e-12)
    np.testing.assert_allclose(record.channels["top_speed"], v["rpm"] * RPM, rtol=1e-6)
    np.testing.assert_allclose(record.channels["surface_torque"], v["torque"] * 1e3, rtol=1e-6)
    np.testing.assert_allclose(record.channels["hook_load"], v["hook"] * 1e3, rtol=1e-9)
    np.testing.assert_allclose(record.channels["block_position"], v["block"], rtol=1e-6)
    np.testing.assert_allclose(record.channels["standpipe_pressure"], v["spp"] * 1e6, rtol=1e-6)
    assert all(np.all(f == USABLE) for f in record.flags.values())
    assert any("surface_torque: column Surf Torque [kN*m]" in note for note in record.notes)


@pytest.mark.parametrize("channel", list(CHANNELS))
def test_each_mnemonic_table_names_its_channel(tmp_path, channel):
    t, v = _rows()
    units = {"top_speed": "rpm", "surface_torque": "kN*m", "hook_load": "kN", "block_position": "m",
             "standpipe_pressure": "MPa"}
    values = dict(zip(CHANNELS, v.values()))
    for mnemonic in MNEMONICS[channel]:
        header = f"ETIM [s],{mnemonic.lower()} [{units[channel]}]"
        record = read_surface_record(_write(tmp_path, _csv(header, t, [values[channel]])))
        assert list(record.channels) == [channel], mnemonic


def test_user_mapping_names_columns_the_mnemonics_do_not(tmp_path):
    t, v = _rows()
    header = "clock [s],quill [rpm],tq_x [kN*m],weight [kN]"
    path = _write(tmp_path, _csv(header, t, [v["rpm"], v["torque"], v["hook"]]))
    with pytest.raises(ValueError, match="no time column"):
        read_surface_record(path)
    record = read_surface_record(path, columns={"time": "clock", "top_speed": "quill", "surface_torque": "TQ_X",
                                                "hook_load": "weight"})
    assert set(record.channels) == {"top_speed", "surface_torque", "hook_load"}
    np.testing.assert_allclose(record.channels["top_speed"], v["rpm"] * RPM, rtol=1e-6)
    with pytest.raises(ValueError, match="column 'nope' is not in the header"):
        read_surface_record(path, columns={"time": "clock", "top_speed": "nope"})
    with pytest.raises(ValueError, match="unknown channel 'bit_speed'"):
        read_surface_record(path, columns={"bit_speed": "quill"})


def test_field_units_are_converted_to_si(tmp_path):
    t, _ = _rows(n=30)
    rpm, kftlbf, klbf, ft, psi = 120.0, 15.0, 374.0, 90.0, 3000.0
    header = "TIME [s],RPM [rpm],TQ [kft*lbf],HKLD [klbf],BPOS [ft],SPP [psi]"
    rng = np.random.default_rng(1)
    cols = [x + 1e-3 * x * rng.standard_normal(len(t)) for x in (rpm, kftlbf, klbf, ft, psi)]
    record = read_surface_record(_write(tmp_path, _csv(header, t, cols, "{:.9g}")))
    np.testing.assert_allclose(record.channels["top_speed"], cols[0] * RPM, rtol=1e-8)
    np.testing.assert_allclose(record.channels["surface_torque"], cols[1] * 1e3 * FOOT * LBF, rtol=1e-8)
    np.testing.assert_allclose(record.channels["hook_load"], cols[2] * 1e3 * LBF, rtol=1e-8)
    np.testing.assert_allclose(record.channels["block_position"], cols[3] * FOOT, rtol=1e-8)
    np.testing.assert_allclose(record.channels["standpipe_pressure"], cols[4] * PSI, rtol=1e-8)


def test_units_given_override_the_header_and_say_so(tmp_path):
    t, v = _rows()
    path = _write(tmp_path, _csv("TIME [min],HKLD [kN]", t, [v["hook"]]))
    record = read_surface_record(path, units={"hook_load": "klbf"})
    np.testing.assert_allclose(record.channels["hook_load"], v["hook"] * 1e3 * LBF, rtol=1e-9)
    np.testing.assert_allclose(record.time, t * 60.0, atol=1e-9)  # the header's time unit
    assert any("unit klbf given (the header of column HKLD says kN)" in note for note in record.notes)


def test_a_units_line_under_the_header_is_read(tmp_path):
    t, v = _rows()
    text = _csv("TIME,RPM,HKLD", t, [v["rpm"], v["hook"]]).replace("\n", "\ns,rpm,klbf\n", 1)
    record = read_surface_record(_write(tmp_path, text))
    np.testing.assert_allclose(record.channels["hook_load"], v["hook"] * 1e3 * LBF, rtol=1e-9)
    assert len(record.time) == len(t)


def test_a_unit_of_the_wrong_dimension_is_refused_naming_column_and_unit(tmp_path):
    t, v = _rows()
    path = _write(tmp_path, _csv("TIME [s],HKLD [m]", t, [v["hook"]]))
    with pytest.raises(ValueError, match=r"column HKLD \(hook_load\): unit 'm' is a length unit, not a force unit"):
        read_surface_record(path)
    path = _write(tmp_path, _csv("TIME [s],TQ [kN]", t, [v["torque"]]))
    with pytest.raises(ValueError, match=r"column TQ \(surface_torque\).*'kN'"):
        read_surface_record(path)
    with pytest.raises(ValueError, match=r"column TQ \(surface_torque\).*'psi'"):
        read_surface_record(path, units={"surface_torque": "psi"})


def test_a_channel_without_unit_is_refused_except_rpm(tmp_path):
    t, v = _rows()
    with pytest.raises(ValueError, match=r"column HKLD \(hook_load\) has no unit"):
        read_surface_record(_write(tmp_path, _csv("TIME,HKLD", t, [v["hook"]])))
    record = read_surface_record(_write(tmp_path, _csv("TIME,TD_RPM", t, [v["rpm"]])))
    np.testing.assert_allclose(record.channels["top_speed"], v["rpm"] * RPM, rtol=1e-6)


def test_iso_timestamps_are_seconds_from_the_first_sample(tmp_path):
    stamps = ["2026-12-04T17:53:24.000Z", "2026-12-04T17:53:24.250Z", "2026-12-04T17:53:24.500Z",
              "2026-12-04T17:53:24.800Z", "2026-12-04 17:53:25.000+00:00"]
    text = "TIMESTAMP,RPM [rpm]\n" + "\n".join(f"{s},{100 + k * 0.1}" for k, s in enumerate(stamps)) + "\n"
    record = read_surface_record(_write(tmp_path, text))
    np.testing.assert_allclose(record.time, [0.0, 0.25, 0.5, 0.8, 1.0], atol=1e-9)
    assert any("timestamps from 2026-12-04T17:53:24" in note for note in record.notes)


def test_times_must_increase_and_be_readable(tmp_path):
    text = "TIME [s],RPM [rpm]\n0,100\n0.1,100\n0.1,100\n"
    with pytest.raises(ValueError, match=r"line 4: time '0.1' does not come after '0.1'"):
        read_surface_record(_write(tmp_path, text))
    text = "TIME [s],RPM [rpm]\n0,100\nsoon,100\n"
    with pytest.raises(ValueError, match=r"line 3: time 'soon' is neither a number nor an ISO 8601 timestamp"):
        read_surface_record(_write(tmp_path, text))


def test_irregular_sampling_is_no_gap(tmp_path):
    rng = np.random.default_rng(3)
    t = np.cumsum(0.1 * (1.0 + 0.4 * (rng.random(300) - 0.5)))  # steps 0.08-0.12 s
    text = _csv("TIME [s],HKLD [kN]", t, [1664.0 + rng.standard_normal(300)])
    record = read_surface_record(_write(tmp_path, text))
    assert len(record.time) == 300 and np.all(record.flags["hook_load"] == USABLE)


def test_empty_and_non_numeric_cells_are_missing(tmp_path):
    t, v = _rows()
    rows = _csv("TIME [s],HKLD [kN],RPM [rpm]", t, [v["hook"], v["rpm"]]).splitlines()
    rows[5] = f"{t[4]:.3f},,{v['rpm'][4]:.6f}"
    rows[8] = f"{t[7]:.3f},n/a,-999.25"
    record = read_surface_record(_write(tmp_path, "\n".join(rows) + "\n"))
    assert np.nonzero(record.flags["hook_load"] == MISSING)[0].tolist() == [4, 7]
    assert np.nonzero(record.flags["top_speed"] == MISSING)[0].tolist() == [7]
    assert not record.usable("hook_load")[[4, 7]].any()
    assert sum("empty or non-numeric" in note for note in record.notes) == 2


def test_ambiguous_columns_are_refused(tmp_path):
    t, v = _rows()
    path = _write(tmp_path, _csv("TIME [s],RPM [rpm],TD_RPM [rpm]", t, [v["rpm"], v["rpm"]]))
    with pytest.raises(ValueError, match="columns RPM, TD_RPM could each be the top_speed"):
        read_surface_record(path)
    assert "top_speed" in read_surface_record(path, columns={"top_speed": "TD_RPM"}).channels


def test_the_file_is_read_through_the_bounded_reader(tmp_path):
    with pytest.raises(ValueError, match="surface record .* is not a regular file"):
        read_surface_record(tmp_path)
    with pytest.raises(ValueError, match="surface record not found"):
        read_surface_record(tmp_path / "none.csv")


def test_parquet_needs_pyarrow_or_reads(tmp_path):
    path = tmp_path / "record.parquet"
    t, v = _rows()
    if importlib.util.find_spec("pandas") is None or importlib.util.find_spec("pyarrow") is None:
        path.write_bytes(b"PAR1 not really")
        with pytest.raises(ValueError, match=r"reading Parquet needs .*pyarrow.*pip install"):
            read_surface_record(path)
        return
    import pandas as pd  # pragma: no cover - where pyarrow is installed

    pd.DataFrame({"TIME [s]": t, "HKLD [kN]": v["hook"]}).to_parquet(path)
    record = read_surface_record(path)
    np.testing.assert_allclose(record.channels["hook_load"], v["hook"] * 1e3, rtol=1e-12)
