"""The shipped synthetic surface record (drillstring.estimation.synthetic): it reads with its faults flagged
exactly where the generator put them and nowhere else, its measured channels are the truth plus the stated
bias and noise, the truth is consistent with itself (the block follows the bit, the top drive holds its set point,
the bit sticks), and a short regeneration with the same seed gives the shipped file's first rows."""

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


def test_a_short_regeneration_gives_the_first_rows():
    short = make_synthetic_record(seed=SEED, duration=3.0)
    text = record_text(short)
    shipped = CASES.joinpath("stick_slip_surface.csv").read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if not line.startswith("#")]
    first = [line for line in shipped.splitlines() if not line.startswith("#")][: len(rows)]
    assert rows[0] == first[0] == ",".join(f"{c} [{u}]" for c, u in FILE_COLUMNS.values())
    assert len(rows) == 32  # the header and 31 samples, 0 to 3 s
    for ours, theirs in zip(rows[1:], first[1:]):
        for (name, _), a, b in zip(FILE_COLUMNS.items(), ours.split(","), theirs.split(",")):
            if a != b:  # a last decimal may flip on another floating-point library
                assert abs(float(a) - float(b)) <= 1.01 * 10.0 ** -DECIMALS[name], (name, a, b)
