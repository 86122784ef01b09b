"""The surface torque of a top drive (issue 25, item 6): from the quill's equation of motion,
``T_s = τ_m − J_td θ̈₀``, it does not depend on the top drive's inertia for the same quill and bit motion.
(Read as the elastic torque of the top element from the truncated basis, it did: on this string 4374 N·m at
100 kg·m² and 4548 N·m at 1000 kg·m² in the same steady drilling, whose surface torque is 4593 N·m.)"""

import numpy as np
import pytest

from drillstring.dynamics.rom import OBSERVABLE_COLUMN, case_reduced_model, rigid_axial_column
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.stability import _steady_load, steady_drilling


def _model(reference_case, inertia: float):
    """The reference string (coarse mesh, 6 torsional modes, no lateral) under a stiff PI top drive
    (k_p = 3e4 N*m*s/rad, k_i = 3e5 N*m/rad: the quill nearly at the set point) of inertia ``inertia``."""
    return case_reduced_model(reference_case.model_copy(update={
        "mesh": reference_case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": reference_case.reduced_model.model_copy(
            update={"axial_modes": 3, "torsional_modes": 6, "lateral_modes": 0, "lateral_cutoff": 0.0}),
        "top_drive": reference_case.top_drive.model_copy(update={
            "controller": "pi", "inertia": inertia, "proportional_gain": 3e4, "integral_gain": 3e5}),
    }))


@pytest.fixture(scope="module")
def runs(reference_case):
    return {j: (_model(reference_case, j), simulate_model(_model(reference_case, j), t_end=8.0, output_step=0.05))
            for j in (100.0, 1000.0)}


def test_steady_surface_torque_is_the_motor_torque(runs):
    """In steady drilling the quill does not accelerate: T_s is the motor torque the rigid rotation's
    equation asks for (torque on bit and rigid-rotation friction), whatever J_td."""
    for model, _ in runs.values():
        steady = steady_drilling(model)
        motor = _steady_load(model, steady.bit_speed, rigid_axial_column(model))[3]
        torque = model.observe(0.0, steady.state)[OBSERVABLE_COLUMN["surface_torque"]]
        assert torque == pytest.approx(motor, rel=1e-9)
        assert torque == pytest.approx(steady.torque_on_bit, rel=2e-3)  # + the small rigid-rotation friction


def test_surface_torque_does_not_depend_on_the_top_drive_inertia(runs):
    """The start-up transient (8 s, the bit speed swinging 3–18 rad/s) with J_td = 100 and 1000 kg*m2: the
    quill and the bit move the same way (to 1.5 % and 0.1 % of their swings), and so does T_s (its 11 kN*m
    swing agrees to 0.2 %)."""
    (_, light), (_, heavy) = runs[100.0], runs[1000.0]
    assert light.status == heavy.status == "success"

    def close(name, share):
        a, b = light.observables[name], heavy.observables[name]
        swing = max(np.ptp(a), np.ptp(b))
        assert np.max(np.abs(a - b)) < share * swing, name
        return swing

    close("quill_speed", 0.015)
    assert close("bit_speed", 1e-3) > 10.0
    assert close("surface_torque", 2e-3) > 1e4
