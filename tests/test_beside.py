"""The second process that draws a study's figures beside the rest of its end (drillstring.outputs.beside): its
result is the function's; the caller computes it where the process is disabled or dies; an error of the work is
raised in the caller; the study's figures are the same files drawn there or here."""

import filecmp
import os

import pytest

from drillstring.outputs.beside import ProcessBeside


def where(parent_pid: int) -> str:
    return "child" if os.getpid() != parent_pid else "caller"


def die_unless_in(parent_pid: int) -> str:
    if os.getpid() != parent_pid:
        os._exit(3)  # kills the process beside
    return "caller"


def fail(message: str) -> None:
    raise ValueError(message)


def test_work_runs_beside_and_falls_back_to_the_caller():
    me = os.getpid()
    with ProcessBeside() as beside:
        assert beside.submit(where, me)() == ("child" if (os.cpu_count() or 1) > 1 else "caller")
        assert beside.submit(die_unless_in, me)() == "caller"  # the process died: done here
        assert beside.submit(where, me)() == "caller"  # and it stays gone
    with ProcessBeside(enabled=False) as beside:
        assert beside.submit(where, me)() == "caller"


def test_an_error_of_the_work_reaches_the_caller():
    with ProcessBeside() as beside:
        result = beside.submit(fail, "bad statistics")
        with pytest.raises(ValueError, match="bad statistics"):
            result()


def test_study_figures_drawn_beside_equal_those_drawn_here(tmp_path):
    from drillstring.case import load_case
    from drillstring.outputs.study_plots import plot_study
    from drillstring.stochastic import montecarlo as mc
    from drillstring.stochastic.analysis import load_study, study_statistics, time_convergence
    from drillstring.stochastic.execution import Engine

    case = load_case("reference")
    settings = mc.StudySettings(samples=4, t_end=1.0, output_step=0.05,
                                laws=(mc.weight_on_hook_normal(case, 5000.0),))
    mc.run_study(case, settings, tmp_path / "study.zarr", Engine(workers=1))
    stats = study_statistics(load_study(tmp_path / "study.zarr"), t_transient=0.5)
    arguments = (stats, 0.5, time_convergence(stats, 0.5))
    with ProcessBeside() as beside:
        beside_figures = beside.submit(plot_study, arguments[0], tmp_path / "beside", *arguments[1:])()
    here = plot_study(arguments[0], tmp_path / "here", *arguments[1:])
    assert set(here) == set(beside_figures) == {"convergence", "envelopes", "dispersion", "realizations"}
    assert all(filecmp.cmp(here[k], beside_figures[k], shallow=False) for k in here)
