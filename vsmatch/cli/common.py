"""What every command shares: one-line errors and exit statuses, the common options,
and small checks of output paths."""

from __future__ import annotations

import functools
import math
import os
import signal
import sys
from pathlib import Path

import click

from .. import batch, datasets, io
from ..config import ConfigError, bundled_config_names, config_from_dict
from ..executors import ExecutorError
from .console import TERMINATING

EXPECTED_ERRORS = (ConfigError, io.ImageError, datasets.DatasetError, batch.BatchError,
                   ExecutorError, ValueError, OSError)

#: Exit status after Ctrl-C (128 + SIGINT) and SIGTERM (128 + 15), as shells report them
#: (SIGHUP 129, SIGQUIT 131 likewise).
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
#: Exit status when the reader of our output went away (128 + SIGPIPE), as shells report it.
EXIT_BROKEN_PIPE = 141


def examples(*lines: str) -> str:
    """A command's epilog: the lines kept as written (Click's ``\\b``), under "Examples"."""
    return "\b\nExamples:\n" + "\n".join(f"  {line}" for line in lines)


class Terminated(KeyboardInterrupt):
    """SIGTERM (or another of :data:`TERMINATING`), raised in the main thread so that it
    unwinds like Ctrl-C: temporaries are removed and the worker processes are ended on
    the way out."""

    def __init__(self, signum: int = signal.SIGTERM):
        super().__init__()
        self.signum = signum


def on_sigterm(signum, frame):
    # A second SIGTERM while the first unwinds (or while Python shuts its threads down)
    # would raise inside that clean-up and print a traceback: it is ignored from here on.
    # First by a handler that does nothing, which consumes a second signal caught while
    # this one was being handled (with SIG_IGN at once, Python would later raise OSError
    # "ignored due to race condition" for it, wherever it next checked for signals); then
    # by SIG_IGN, which Python keeps while it shuts down (its own handlers it resets to
    # the default, which would kill the process on a late second signal).
    for number in TERMINATING:
        signal.signal(number, ignore_signal)
        signal.signal(number, signal.SIG_IGN)
    STOPS.append(signum)
    raise Terminated(signum)


def on_sigint(signum, frame):
    """Ctrl-C, as Python's own handler, but recorded (see :data:`STOPS`)."""
    STOPS.append(signum)
    raise KeyboardInterrupt()


#: SIGTERMs and SIGINTs received. Raised where the handler ran, the exception can still be
#: lost: inside a ctypes callback (Numba's compiler calls back into Python) Python reports
#: it as unraisable and carries on. So it is raised again before any output lands and when
#: the command returns (:func:`raise_if_stopped`), and not reported
#: (:func:`quiet_unraisable_stops`).
STOPS: list[int] = []


def raise_if_stopped() -> None:
    for number in STOPS:
        if number in TERMINATING:
            raise Terminated(number)
    if STOPS:
        raise KeyboardInterrupt()


io.add_stop_check(raise_if_stopped)


def quiet_unraisable_stops(hook):
    """``sys.unraisablehook`` that keeps a stop lost in a callback off stderr (it is raised
    again, :data:`STOPS`), and after a stop whatever a finalizer raises as Python shuts
    down, and hands anything else to ``hook``. A signal can land inside a finalizer's own
    teardown: llvmlite's ``ObjectRef`` half-closed by it failed again at shutdown
    (``AttributeError: ... _as_parameter_``), a traceback after the one line (seen once in
    a clean clone's test run)."""
    def unraisable(info):
        if info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt):
            return
        if STOPS:  # stopping: the one line is said; what the teardown trips on is not news
            return
        hook(info)
    unraisable.quiet_stops = True
    return unraisable


def ignore_signal(signum, frame) -> None:
    """A signal handler that does nothing."""


def stop(exc: BaseException) -> None:
    """The one line and exit status of an interruption."""
    note = getattr(exc, NOTE, "")
    if isinstance(exc, Terminated):
        click.echo(f"vsmatch: {TERMINATING.get(exc.signum, 'terminated')}{note}", err=True)
        sys.exit(128 + int(exc.signum))
    click.echo(f"vsmatch: interrupted{note}", err=True)
    sys.exit(EXIT_INTERRUPTED)


#: The attribute that carries what a command adds to the one line of its failure.
NOTE = "vsmatch_note"


def add_note(exc: BaseException, text: str) -> None:
    """Say ``text`` after the one line of ``exc`` (an error or an interruption)."""
    setattr(exc, NOTE, f"{getattr(exc, NOTE, '')}; {text}")


def debugging() -> bool:
    ctx = click.get_current_context(silent=True)
    flag = bool(ctx and (ctx.find_root().obj or {}).get("debug"))
    return flag or os.environ.get("VSMATCH_DEBUG", "") not in ("", "0")


def friendly_errors(func):
    """Turn the library's expected errors into one-line ClickExceptions (exit 1), any
    other exception into one line naming the command (the traceback under --debug), and
    Ctrl-C or SIGTERM into a one-line notice with exit status 130 or 143."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            result = func(*args, **kwargs)
            raise_if_stopped()  # a signal whose exception was swallowed on the way
            return result
        except BrokenPipeError:  # `vsmatch ... | head`: the reader has what it wanted
            try:  # Python's own flush at exit must stay quiet too
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            except (AttributeError, OSError, ValueError):  # no real stdout
                pass
            sys.exit(EXIT_BROKEN_PIPE)
        except click.ClickException as exc:
            if getattr(exc, NOTE, ""):
                exc.message += getattr(exc, NOTE)
            raise
        except EXPECTED_ERRORS as exc:
            if debugging():
                raise
            raise click.ClickException(one_line(exc) + getattr(exc, NOTE, "")) from None
        except KeyboardInterrupt as exc:
            stop(exc)
        except (Exception, RecursionError, MemoryError) as exc:
            if debugging():
                raise
            ctx = click.get_current_context(silent=True)
            where = " ".join(["vsmatch"] + (ctx.command_path.split()[1:] if ctx else []))
            raise click.ClickException(
                f"{where}: unexpected {type(exc).__name__}: {one_line(exc)[:300]} "
                f"(--debug shows the traceback){getattr(exc, NOTE, '')}") from None
    return wrapper


def verbosity_options(func):
    """-v, -q and --debug after the command name too (``vsmatch run ... -v``)."""
    def setter(key):
        def callback(ctx, param, value):
            if value:
                root = ctx.find_root().obj
                root[key] = True
                if key == "quiet":
                    root["verbose"] = False
                elif key == "verbose":
                    root["verbose"] = not root.get("quiet")
        return callback
    for names, key, text in ((("-q", "--quiet"), "quiet", "Print only errors."),
                             (("-v", "--verbose"), "verbose", "Print more (stage times, "
                              "the range found, ...) on stderr."),
                             (("--debug",), "debug", "Show the traceback of an "
                              "unexpected error.")):
        func = click.option(*names, key + "_flag", is_flag=True, expose_value=False,
                            callback=setter(key), help=text)(func)
    return func


class Finite(click.ParamType):
    """A finite float (nan and inf refused), optionally above a bound."""

    name = "NUMBER"

    def __init__(self, positive: bool = False):
        self.positive = positive

    def convert(self, value, param, ctx):
        if isinstance(value, float) and math.isfinite(value):
            number = value
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                self.fail(f"'{value}' is not a number", param, ctx)
            if not math.isfinite(number):
                self.fail(f"'{value}' is not a finite number", param, ctx)
        if self.positive and number <= 0:
            self.fail(f"{number:g} must be greater than 0", param, ctx)
        return number


FINITE, POSITIVE = Finite(), Finite(positive=True)


class FiniteRange(Finite):
    """A finite number in [low, high] (NaN refused, unlike click.FloatRange)."""

    def __init__(self, low: float, high: float, name: str = "NUMBER"):
        super().__init__()
        self.low, self.high, self.name = low, high, name

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not self.low <= number <= self.high:
            self.fail(f"{number:g} is not in [{self.low:g}, {self.high:g}]", param, ctx)
        return number


CONFIDENCE_LEVEL = FiniteRange(0, 1, "C")
ALPHA = FiniteRange(0, 1, "ALPHA")


def given(ctx: click.Context, name: str) -> bool:
    """Whether the option ``name`` was given on the command line (not its default)."""
    source = ctx.get_parameter_source(name)
    return source is not None and source != click.core.ParameterSource.DEFAULT


def one_line(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return " ".join(text.split())


def echo(ctx: click.Context, message: str, *, err: bool = False) -> None:
    if not ctx.find_root().obj.get("quiet"):
        click.echo(message, err=err)


def verbose(ctx: click.Context, message: str) -> None:
    if ctx.find_root().obj.get("verbose"):
        click.echo(message, err=True)


def config_option(func):
    return click.option(
        "--config", "config", default=None, metavar="NAME|PATH",
        help=f"Method parameters: a bundled config ({', '.join(bundled_config_names())}) "
             "or a YAML file. Default: 'default'.")(func)


def max_memory_option(func):
    return click.option(
        "--max-memory", type=click.IntRange(min=16, max=1 << 20), default=None, metavar="MB",
        help="Working-memory budget of the matching in MB (the config's memory.max_mb, "
             "default 1024); larger images are matched in horizontal stripes.")(func)


def scheduler_address(value: str | None) -> str | None:
    from ..executors.cluster import check_scheduler

    if value is not None:
        try:
            check_scheduler(value)
        except ExecutorError as exc:
            raise click.BadParameter(str(exc).split(": ", 1)[1],
                                     param_hint="'--scheduler'") from None
    return value


def with_budget(cfg, max_memory: int | None):
    """The config with ``--max-memory`` as its memory budget, if given."""
    if max_memory is None:
        return cfg
    return config_from_dict({"memory": {"max_mb": max_memory}}, base=cfg)


def data_root_option(func):
    return click.option(
        "--data-root", type=click.Path(file_okay=False), default=None,
        help="Folder holding middlebury2/ (and middlebury-2005-2006-third/). Default: "
             "$VSMATCH_DATA, else ./data, else ../shared/data.")(func)


class MaxDisparity(click.ParamType):
    """``--max-disp``: a whole number of pixels, or ``auto`` (None)."""

    name = "N|auto"

    def convert(self, value, param, ctx):
        if value is None or isinstance(value, int):
            return value
        if str(value).strip().lower() == "auto":
            return None
        try:
            number = int(value)
        except ValueError:
            self.fail(f"'{value}' is neither a whole number nor 'auto'", param, ctx)
        if number <= 0:
            self.fail(f"{number} must be at least 1", param, ctx)
        return number


MAX_DISP = MaxDisparity()


class OneLineErrors(click.Group):
    """A group whose every error is one line on stderr: Click's usage errors too, which
    it would otherwise print over four lines with the usage text."""

    def main(self, *args, **kwargs):
        kwargs["standalone_mode"] = False
        try:
            result = super().main(*args, **kwargs)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "vsmatch"
            click.echo(f"Error: {exc.format_message()} (see '{where} --help')", err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except KeyboardInterrupt as exc:
            stop(exc)
        except click.Abort:
            stop(KeyboardInterrupt())
        except (Exception, RecursionError, MemoryError) as exc:
            # Outside a command (option parsing, start-up): still one line.
            argv = kwargs.get("args", args[0] if args else None)
            argv = sys.argv[1:] if argv is None else list(argv)
            if os.environ.get("VSMATCH_DEBUG", "") not in ("", "0") or "--debug" in argv:
                raise
            click.echo(f"vsmatch: unexpected {type(exc).__name__}: {one_line(exc)[:300]} "
                       "(--debug shows the traceback)", err=True)
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)


def check_outputs(inputs, outputs, *, folders=()) -> None:
    """Every output a file name in an existing, writable folder, none an existing folder,
    and none naming an input or another output (links and ``..`` resolved): the one check
    every command makes before its work. ``folders`` maps an output folder that is made
    when missing to the files written in it. ``None`` entries are ignored."""
    folders = dict(folders)
    for path in outputs:
        if path is not None:
            check_writable_folder(Path(path))
    for folder in folders:
        check_new_folder(Path(folder))
    files = [p for p in outputs if p is not None]
    files += [f for written in folders.values() for f in written]
    try:
        io.check_distinct_paths(inputs, files)
    except ValueError as exc:
        raise click.ClickException(str(exc)) from None


def check_new_folder(folder: Path) -> None:
    """An output folder that exists or can be made: not a file nor a link to nothing, and
    the nearest existing folder above it writable."""
    try:
        folder = io.followed_folder(folder)
    except OSError as exc:
        raise click.ClickException(str(exc)) from None
    if folder.exists() and not folder.is_dir():
        raise click.ClickException(f"{folder}: is a file, not a folder")
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir() or not writable(existing):
        raise click.ClickException(f"{folder}: folder '{existing}' is not writable")


def check_outside(folder: Path, outputs, what: str) -> None:
    """Refuse an output inside ``folder`` (a data set that is read, say)."""
    root = io.resolved(folder)
    for path in outputs:
        if path is not None and io.resolved(path).is_relative_to(root):
            raise click.ClickException(f"{path}: the output would write into the {what} "
                                       f"{folder}, which is read")


def writable(folder: Path) -> bool:
    return os.access(folder, os.W_OK)


def check_writable_folder(path: Path) -> None:
    """``path`` a file name (not a folder) in an existing, writable folder
    (:func:`vsmatch.io.check_output_file`, as a one-line usage error)."""
    try:
        folder = io.check_output_file(path)
    except OSError as exc:
        raise click.ClickException(str(exc)) from None
    if not writable(folder):
        raise click.ClickException(f"{path}: output folder '{folder}' is not writable")


def check_png_range(path, min_disp: int, max_disp: int) -> None:
    problem = io.png_range_problem(path, min_disp, max_disp)
    if problem is not None:
        raise click.ClickException(problem)


def remove_left_overs(ctx: click.Context, paths) -> None:
    """Remove, naming each on stderr, what writes of ``paths`` left when their run was
    killed (SIGKILL: nothing could clean up); None entries are skipped."""
    for path in paths:
        if path is not None:
            for left_over in io.remove_stale_temporaries(path):
                echo(ctx, f"removed {left_over}, left by an earlier run that was killed",
                     err=True)


def announce_compilation(ctx: click.Context, config: str | None = None, bands: bool = True,
                         stream: bool = False, also: tuple[str, ...] = ()) -> None:
    """Before the first run: one line, then the kernels ``config`` (a bundled name or a
    file) calls compiled a share a core (``vsmatch.compilation``; half a minute of silence
    else): with ``bands`` those of bands above a level down, with ``stream`` a video
    stream's too, and a whole-range match's of each config of ``also``."""
    from .. import compilation
    from .._kernels import cache_is_cold

    if cache_is_cold():
        cores = compilation.available_cores()
        echo(ctx, f"compiling the kernels once, on {cores} core{'s' * (cores > 1)} "
                  "(later runs start at once)", err=True)
        seconds = compilation.compile_ahead(config, bands, stream, also=also)
        verbose(ctx, f"compiled in {seconds:.1f} s")
