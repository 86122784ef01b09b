"""The engine commands' progress on stderr: after the last realization the bar names what runs next
(statistics, figures, report), and a rerun that computes nothing shows it on a spinner."""

import io

from rich.console import Console

from drillstring.cli.engine import _StudyProgress


def _console():
    return Console(file=io.StringIO(), force_terminal=True, width=80)


def test_the_bar_names_the_stage_after_the_last_task():
    tracker = _StudyProgress(_console(), "realizations")
    tracker(0, 0, 50)
    tracker(50, 0, 50)
    assert tracker.bar.tasks[0].description == "realizations"
    tracker.stage("figures")
    assert tracker.bar.tasks[0].description == "figures…" and tracker.status is None
    tracker.stop()


def test_a_run_without_tasks_shows_its_stages_on_a_spinner():
    console = _console()
    tracker = _StudyProgress(console, "realizations")
    tracker.stage("reading the store")
    assert tracker.bar is None and tracker.status is not None
    tracker.stage("report")
    assert "report…" in str(tracker.status.renderable.text)
    tracker.stop()
