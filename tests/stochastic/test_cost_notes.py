"""Before a study runs, the driver says what makes each of its runs costly and which keys trade accuracy for
time (docs/performance.md, "The README's first case")."""

from drillstring.case import load_case
from drillstring.stochastic.runs import compile_kernels, cost_notes


def _with(case, table, **values):
    return case.model_copy(update={table: getattr(case, table).model_copy(update=values)})


def test_cost_notes_name_the_lateral_cut_off_and_the_explicit_method_on_attachment_modes():
    reference = load_case("reference")  # 20 lateral modes, no cut-off, plain basis, dopri5: nothing to say
    assert cost_notes(reference, 20) == []
    cut = _with(reference, "reduced_model", lateral_cutoff=1.5)
    (lateral,) = cost_notes(cut, 83)
    assert lateral.startswith("each run keeps 83 lateral modes per plane (every one below 1.5× the rotation "
                              "frequency: reduced_model.lateral_cutoff), not 20 (lateral_modes)")
    assert "lateral_cutoff = 0 is faster" in lateral
    explicit = _with(reference, "reduced_model", truncation_correction="static")
    (step,) = cost_notes(explicit, 20)
    assert "explicit method 'dopri5'" in step and 'simulation.method = "ark43"' in step
    assert cost_notes(_with(explicit, "simulation", method="ark43"), 20) == []


def test_the_driver_notes_them_before_the_runs(coarse_case):
    case = _with(coarse_case, "reduced_model", lateral_cutoff=1.5, lateral_modes=2)
    notes = []
    compile_kernels(case, note=notes.append)
    assert len(notes) == 1 and notes[0].startswith("each run keeps ") and "not 2 (lateral_modes)" in notes[0]
    compile_kernels(case)  # no note function: nothing said, nothing raised
