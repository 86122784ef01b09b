"""What the commands running the study engine (``study``, ``map``, ``sensitivity``) share: the declared laws of
``--param``/``--correlation``, the progress bar, and running a call of the engine under the output folder's
lock with one-line errors."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from drillstring.cli.options import EXIT_INTERRUPTED, EXIT_RUN_FAILED, _err_console, _fail

def _declared_laws(param: list[str] | None, correlation: list[str] | None):
    """The ``--param`` laws (None when none is given) and the ``--correlation`` table; a malformed value
    ends the command (exit code 2)."""
    from drillstring.stochastic.parameters import ParameterError
    from drillstring.stochastic.uncertainty import correlation_table, split_assignment, split_correlation

    try:
        laws = None
        if param:
            laws = {}
            for text in param:
                path, spec = split_assignment(text)
                if path in laws:
                    raise ParameterError(f"--param {path} is given twice")
                laws[path] = spec
        table = correlation_table([split_correlation(t) for t in correlation]) if correlation else None
    except ParameterError as error:
        _fail(str(error))
    return laws, table


#: The ``--param`` prefix of the model uncertainty's dispersions (the case file's ``[uncertainty.model]``).
MODEL_PREFIX = "uncertainty.model."


def _model_dispersions(laws: dict[str, str] | None) -> tuple[dict[str, str] | None, dict[str, float] | None]:
    """Split the ``--param uncertainty.model.KEY=δ`` values (random reduced matrices) off the laws: ``(laws or
    None, {KEY: δ} or None)``; a value that is not a number ends the command (exit code 2)."""
    if not laws:
        return laws, None
    model = {}
    for path in [p for p in laws if p.startswith(MODEL_PREFIX)]:
        text = laws.pop(path)
        try:
            model[path[len(MODEL_PREFIX):]] = float(text)
        except ValueError:
            _fail(f"--param {path} = {text!r}: must be a number in [0, 1) (a dispersion)")
    return laws or None, model or None


class _StudyProgress:
    """``progress(done, failed, total)`` for the engine's runs: a rich bar (stderr) of the ``noun``
    (realizations, grid points, runs), failures and time left. The bar starts at the first call, so that
    a run refused before it starts prints no empty bar."""

    def __init__(self, console: Console, noun: str = "realizations") -> None:
        self.console = console
        self.noun = noun
        self.bar: Progress | None = None
        self.task = None
        self.status = None

    def __call__(self, done: int, failed: int, total: int) -> None:
        if self.bar is None:
            columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                       TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(), TextColumn("left"),
                       TimeRemainingColumn())
            self.bar = Progress(*columns, console=self.console)
            self.bar.start()
            self.task = self.bar.add_task(escape(self.noun), total=total, completed=done + failed, failed=failed)
        else:
            self.bar.update(self.task, completed=done + failed, failed=failed)

    def stage(self, text: str) -> None:
        """Show what runs after the last task (``text``: "statistics", "figures", ...): in place of the noun on
        the bar, or on a spinner of its own when no task ran (a rerun that computes nothing)."""
        if self.bar is not None:
            self.bar.update(self.task, description=escape(f"{text}…"))
        elif self.status is None:
            self.status = self.console.status(escape(f"{text}…"))
            self.status.start()
        else:
            self.status.update(escape(f"{text}…"))

    def stop(self) -> None:
        if self.bar is not None:
            self.bar.stop()
        if self.status is not None:
            self.status.stop()


def _api():
    from drillstring import api

    return api


def _engine_command(out: Path, store_name: str, what: str, noun: str, call, *, workers: int | None = None,
                    scheduler: str | None = None, units: str | None = None):
    """Run ``call(run)`` (an API function of the study engine) for a command writing to ``out``, ``run`` the
    command's :class:`~drillstring.api.settings.RunOptions` built here, once for every command (``out``,
    ``--workers`` or ``--scheduler``, a progress bar and notes on stderr, ``--units``):
    the store's lock is taken before loading the engine (a second run on the folder is refused at once),
    and every error ends the command with one line: exit 130 when
    interrupted (what finished is saved), 1 for a run that started and failed (an output write that failed:
    disk full, no permission), 2 for refused input (settings, store, scheduler, lock, another kind of run in
    the folder, an output path that is not a regular file). Temporary files left in ``out`` by a killed run
    are removed. A folder created here and left empty is removed."""
    from drillstring.files import LockedError, remove_stale_temporaries, write_error_message
    from drillstring.stochastic import execution
    from drillstring.stochastic.locks import StudyLock, StudyLocked

    from drillstring.api.settings import RunOptions

    if workers is not None and scheduler:
        _fail("give --workers (local processes) or --scheduler (Dask cluster), not both")
    err = _err_console()

    def note(text: str) -> None:
        # wrapped between words on a terminal; one line per note in a log (grep finds it whole)
        err.print(escape(f"note: {text}"), soft_wrap=not err.is_terminal)

    created = not out.exists()
    lock = StudyLock(out / store_name, what=what)
    try:  # taken before loading the engine: a second run on this folder is refused at once
        lock.__enter__()
    except StudyLocked as error:
        _fail(str(error))
    if lock.note:
        note(lock.note)
    tracker = _StudyProgress(err, noun)
    try:
        remove_stale_temporaries(out)
        try:
            return call(RunOptions(out=out, workers=workers, scheduler=scheduler, progress=tracker, note=note,
                                   units=units, stage=tracker.stage))
        finally:
            tracker.stop()
    except execution.Interrupted as error:
        _fail(str(error), EXIT_INTERRUPTED)
    except KeyboardInterrupt:
        _fail(f"interrupted; finished {noun} are saved in {out / store_name}; run the same command again to "
              "resume", EXIT_INTERRUPTED)
    except (execution.WorkersLost, _api().StudyFailed) as error:
        _fail(str(error), EXIT_RUN_FAILED)
    except OSError as error:  # an output write that failed: disk full, no permission, read-only filesystem
        _fail(write_error_message(error, f"finished {noun} are kept in {out / store_name}"), EXIT_RUN_FAILED)
    except (ValueError, LockedError) as error:  # settings, store, scheduler or lock refused
        _fail(str(error))
    finally:
        lock.__exit__(None, None, None)
        if created and out.is_dir() and not any(out.iterdir()):  # refused before anything was written
            out.rmdir()
