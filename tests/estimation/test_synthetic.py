"""The shipped synthetic surface record (drillstring.estimation.synthetic): it reads with its faults flagged
exactly where the generator put them and nowhere else, its measured channels are the truth plus the stated
bias and noise, the truth is consistent with itself (the block follows the bit, the top drive holds its set point,
the bit sticks), and a short regeneration with the same seed gives the shipped file's first rows (the added noise
and faults to the file's rounding, the chaotic truth to what differs between processors)."""

from __future__ import annotations

from importlib import resources

import numpy as np
import pytest

from drillstring.estimation.reading import read_surface_record
from drillstring.estimation.synthetic import (
    DECIMALS, FILE_COLUMNS, HOOK_LOAD_BIAS, NOISE, SEED, make_synthetic_record, read_truth, record_text,
)

CASES = resources.files("drillstring").joinpath("cases")


@pytest.fixture(scope="module")
def shipped():
    truth = read_truth(CASES.joinpath("stick_slip_surface_truth.csv"))
    record = read_surface_record(CASES.joinpath("stick_slip_surface.csv"), case="stick_slip")
    return record, truth


def test_the_shipped_record_reads_with_its_faults_where_they_were_put(shipped):
    record, (_, truth) = shipped
    np.testing.assert_allclose(record.time, truth["time"], atol=1e-9)
    for name in NOISE:
        np.testing.assert_array_equal(record.flags[name], truth[f"fault_{name}"].astype(np.int8), err_msg=name)
    put = {name: int(np.count_nonzero(truth[f"fault_{name}"])) for name in NOISE}
    assert put == {"top_speed": 52, "surface_torque": 24, "hook_load": 23, "block_position": 23}  # 22 in the gaps


def test_the_measured_channels_are_truth_plus_bias_and_noise(shipped):
    record, (parameters, truth) = shipped
    assert float(parameters["hook_load_bias"].split()[0]) == HOOK_LOAD_BIAS
    for name, sigma in NOISE.items():
        usable = record.usable(name)
        residual = record.channels[name][usable] - truth[name][usable]
        n = usable.sum()
        bias = HOOK_LOAD_BIAS if name == "hook_load" else 0.0
        assert abs(residual.mean() - bias) < 4.0 * sigma / np.sqrt(n), name
        assert residual.std() == pytest.approx(sigma, rel=0.1), name


def test_the_truth_is_consistent(shipped):
    _, (parameters, truth) = shipped
    t = truth["time"]
    span = t[-1] - t[0]
    descent = -(truth["block_position"][-1] - truth["block_position"][0]) / span
    advance = (truth["bit_depth"][-1] - truth["bit_depth"][0]) / span
    assert descent == pytest.approx(advance, rel=0.01)  # the block follows the bit
    assert advance == pytest.approx(truth["rate_of_penetration"].mean(), rel=0.02)
    set_point = float(parameters["top_speed_set_point"].split()[0])
    assert truth["top_speed"].mean() == pytest.approx(set_point, rel=0.002)  # the PI's integral action
    assert 0.05 < np.mean(truth["bit_speed"] < 0.1) < 0.5  # the bit sticks part of the time
    assert np.all(truth["hook_load"] == truth["hook_load"][0])  # prescribed: the static hook load


def _rows(text: str) -> np.ndarray:
    """The numeric rows of a record file's text (file units; empty cells and -999.25 NaN)."""
    body = [line for line in text.splitlines() if not line.startswith("#")][1:]
    cells = [[float(c) if c and c != "-999.25" else np.nan for c in line.split(",")] for line in body]
    return np.array(cells)


def test_a_short_regeneration_gives_the_first_rows(shipped):
    """The same seed regenerates the shipped file's start: the header; the noise, bias and faults added to the
    truth, to the file's rounding; the truth itself to 1e-3 of each channel's largest value. The truth is a
    stick-slip run 30 s past its start, where the last bits of the model build and the compiled loop (LAPACK's
    and Numba's code differ between processors) grow: measured against the machine that made the file, an AMD
    EPYC (AVX-512) gives the static hook load 7.6e-11 apart (relative) and the surface torque and bit speed
    3.1e-5 of their largest values apart over these 3 s; a 5 % change of the model's dispersion moves them 1e-2,
    a wrong seed changes the noise."""
    from drillstring.estimation.faults import DIMENSION
    from drillstring.units import unit_factor

    _, (_, truth) = shipped
    short = make_synthetic_record(seed=SEED, duration=3.0)
    text = record_text(short)
    shipped_text = CASES.joinpath("stick_slip_surface.csv").read_text(encoding="utf-8")
    header = ",".join(f"{c} [{u}]" for c, u in FILE_COLUMNS.values())
    assert [line for line in text.splitlines() if not line.startswith("#")][0] == header
    assert [line for line in shipped_text.splitlines() if not line.startswith("#")][0] == header
    ours = _rows(text)
    theirs = _rows(shipped_text)[: len(ours)]
    assert ours.shape == (31, 1 + len(NOISE))  # 31 samples, 0 to 3 s
    np.testing.assert_array_equal(ours[:, 0], theirs[:, 0])
    n = len(short.time)
    for j, name in enumerate(NOISE, start=1):
        to_file = 1.0 / unit_factor(FILE_COLUMNS[name][1], DIMENSION[name])
        ours_added = ours[:, j] - short.truth[name][short.present] * to_file
        theirs_added = theirs[:, j] - truth[name][:n][short.present] * to_file
        np.testing.assert_array_equal(np.isnan(ours_added), np.isnan(theirs_added), err_msg=name)
        gap = np.abs(ours_added - theirs_added)[~np.isnan(ours_added)]
        assert gap.max() <= 1.01 * 10.0 ** -DECIMALS[name], name  # two roundings of half the last decimal
    for name, values in short.truth.items():
        scale = np.abs(truth[name]).max()
        assert np.abs(values - truth[name][:n]).max() <= 1e-3 * scale, name
