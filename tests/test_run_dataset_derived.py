"""What a run's Dataset holds besides the observables (issue 25, item 5): the hook load of a ramped start and,
for a Detournay bit, the depth of cut and the wear-flat part of the force on bit, checked against the
closed forms written here (hook load = static hook load + W (1 − min(t/T, 1)); W_c = a ζ ε n d_n)."""

import numpy as np
import pytest

from drillstring import api
from drillstring.case import load_case


def test_detournay_run_has_the_hook_load_depth_of_cut_and_wear_flat_force():
    case = load_case("aarsnes2019")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 3, "torsional_modes": 3}),
        # what the Dataset holds does not depend on the method: DOPRI5, whose loop the other tests compile
        "simulation": case.simulation.model_copy(update={"method": "dopri5"})})
    ds = api.simulate(case, t_end=12.0, output_step=0.05)
    assert ds.attrs["lateral_modes"] == 0
    t = ds.time.values
    wob = case.operation.weight_on_bit
    expected = ds.attrs["weight_on_hook"] + wob * (1 - np.minimum(t / case.initial.weight_ramp_time, 1.0))
    np.testing.assert_allclose(ds.hook_load.values, expected, rtol=1e-12)
    b = case.bit_rock
    depth = ds.depth_of_cut.values
    on_rock = ds.force_on_bit.values > 0
    assert on_rock.any() and (~on_rock).any()  # the bit starts 5 mm above the rock
    assert (depth[~on_rock] <= 0).all() and (depth[on_rock] > 0).all()  # no force on bit: off the rock
    cutting = b.bit_radius * b.cutting_inclination * b.intrinsic_specific_energy * b.blades * depth
    np.testing.assert_allclose(ds.wear_flat_force.values[on_rock], ds.force_on_bit.values[on_rock] - cutting[on_rock],
                               rtol=1e-9, atol=1e-6)
    flats = b.bit_radius * b.contact_stress * b.wear_flat_length  # a σ l: the flats' full contact force
    assert ds.wear_flat_force.values.min() >= -1e-6 and ds.wear_flat_force.values.max() <= flats * (1 + 1e-9)
    assert ds.depth_of_cut.attrs["units"] == "m" and ds.hook_load.attrs["units"] == "N"


def test_tucker_wang_run_has_no_depth_of_cut(coarse_case):
    ds = api.simulate(coarse_case, t_end=0.2)
    assert "depth_of_cut" not in ds and "wear_flat_force" not in ds and "hook_load" not in ds
    assert ds.attrs["lateral_modes"] == coarse_case.reduced_model.lateral_modes
