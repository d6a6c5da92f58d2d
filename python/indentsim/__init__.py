"""indentsim for Python: the same runs, analyses and fits as the command line, as NumPy arrays.

    import indentsim
    r = indentsim.run("loadcases/paper.toml", overrides={"material.E": 200e9})
    r.curve["alpha"], r.curve["P"]          # every column of curve.csv, as arrays
    r.summary["peak_force"]                 # summary.json, as a dict
    r.fields["sigma22"]                     # final state on the nodes, shape (nodes_x, nodes_y)
    r.write("out/paper")                    # the usual files

A case is a load-case file or a dict in the load-case layout ({"material": {"E": 210e9}, ...});
overrides are {"section.key": value} (or the CLI's "section.key=value" strings).  Bad input raises
InputError (a ValueError) with the CLI's message, naming the file and the key.  The solve runs
with the GIL released: runs in two threads solve on two cores.  Units are SI throughout (the
force is N/m per unit thickness in plane strain, N in axisymmetry: see summary["units"]).

Ctrl-C (SIGINT) stops a run() of the main thread as it stops `indentsim run`: after the last
converged increment, which is checkpointed; run() then raises RunInterrupted (a
KeyboardInterrupt) carrying that partial Result.  Signals reach only the main thread:
request_stop() stops every run of this process in progress, whatever thread runs it.

The package is built for one Python (Debian's /usr/bin/python3 unless CMake was told otherwise)
and uses that Python's NumPy; another interpreter (a pyenv python3, a venv without the system's
packages) gets an ImportError that names both and the fix.

Sweeps over many cases, on this machine or a Dask cluster: indentsim.sweep (sweep.py).
"""
import csv
import json
import math
import os
import platform
import re
import shutil
import signal
import sys
import sysconfig
import tempfile
import threading


def _extension_python(suffix):
    """The Python an extension file suffix is for: ".cpython-311-x86_64-linux-gnu.so" is CPython
    3.11 on x86_64-linux-gnu."""
    m = re.fullmatch(r"\.cpython-(\d)(\d+)([a-z]*)-(.+)\.so", suffix)
    if not m:
        return f"the Python whose extension modules end in {suffix}"
    major, minor, flags, system = m.groups()
    return f"CPython {major}.{minor}{flags} on {system}"


def _wrong_python(problem, error):
    """The text of the ImportError raised when this Python cannot use the package: what failed
    (`problem`, Python's `error`), the interpreter running, the one the compiled module was built
    for (from its file name), and how to run that one."""
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        built = sorted(name for name in os.listdir(here) if name.startswith("_indentsim.") and name.endswith(".so"))
    except OSError:
        built = []
    if not built:
        return (f"indentsim cannot be imported: {here} holds no compiled module (_indentsim.*.so).  Build the "
                f"project, and put build/python on PYTHONPATH, not the source folder python/ ({error}).")
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or "?"
    what = f"{problem} ({error})"
    if f"_indentsim{suffix}" not in built:  # Python's own error then says nothing useful about the module
        what = "its compiled module was built for another Python" + (
            f"; also, {what}" if problem.startswith("NumPy") else "")
    running = f"{sys.executable or '(unknown)'}: {platform.python_implementation()} {platform.python_version()}"
    needed = "; ".join(f"{_extension_python(name[len('_indentsim'):])} ({os.path.join(here, name)})" for name in built)
    return (f"indentsim cannot be imported by this Python: {what}.\n"
            f"  this Python:     {running}, extension modules *{suffix}\n"
            f"  indentsim needs: {needed}, with that Python's NumPy\n"
            f"Run the Python indentsim was built with (Debian's /usr/bin/python3 unless CMake was given another "
            f"Python_EXECUTABLE), e.g. `/usr/bin/python3 script.py`; for a virtual environment, make it from that "
            f"Python with the system's packages: `/usr/bin/python3 -m venv --system-site-packages ENV`.  "
            f"See docs/user-guide.md, \"Python: import indentsim\".")


try:
    import numpy as np
except ImportError as e:
    raise ImportError(_wrong_python("NumPy cannot be imported", e)) from None
try:
    from . import _indentsim
except ImportError as e:
    raise ImportError(_wrong_python("its compiled module cannot be loaded", e)) from None
from ._indentsim import InputError, IoError, SolverError

__all__ = ["run", "check", "analyze", "fit", "Result", "InputError", "IoError", "SolverError",
           "NotConvergedError", "RunInterrupted", "request_stop", "version"]


def version():
    """The library's version line (as `indentsim --version`)."""
    return _indentsim.version()


class NotConvergedError(RuntimeError):
    """The solver could not converge (the CLI's exit status 3).  `.result` holds the converged
    increments, as the CLI keeps them."""

    def __init__(self, message, result):
        super().__init__(message)
        self.result = result


class RunInterrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (SIGINT on the main thread) or request_stop(), as `indentsim run`
    stops on SIGINT.  `.result` holds the converged increments (status "stopped"; its folder has
    the checkpoint to resume from, `indentsim resume DIR`), or is None when the run stopped before
    its first increment.  A KeyboardInterrupt: a program that does not catch it stops."""

    def __init__(self, message, result):
        super().__init__(message)
        self.result = result


def request_stop():
    """Stops every run (and fit) of this process in progress, from any thread, as Ctrl-C stops a
    run of the main thread: each ends after its last converged increment and its run() raises
    RunInterrupted.  For runs in worker threads, which no signal reaches.  Returns whether anything
    was in progress; a request never stops a later run."""
    return _indentsim.request_stop()


def _stoppable(call, *args):
    """call(*args), a library call that releases the GIL, and whether SIGINT came meanwhile.

    Off the main thread it is simply called.  On the main thread it runs on a helper thread while
    this one waits, because Python runs signal handlers only between the main thread's bytecodes:
    Python's default SIGINT handler (which raises KeyboardInterrupt) is replaced for the wait by
    one that calls request_stop(), and the call ends as the CLI's run ends on SIGINT.  A SIGINT
    handler of the program's own is left in place and runs at once; if it raises, the call is
    stopped too, and a KeyboardInterrupt counts as SIGINT (anything else is raised after the call).
    """
    if threading.current_thread() is not threading.main_thread():
        return call(*args), False
    done = threading.Event()
    outcome = {}
    interrupted = []

    def work():
        try:
            if hasattr(signal, "pthread_sigmask"):  # SIGINT is for the waiting main thread
                signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            outcome["value"] = call(*args)
        except BaseException as e:  # handed to the main thread
            outcome["error"] = e
        finally:
            done.set()

    def stop(signum, frame):
        interrupted.append(signum)
        _indentsim.request_stop()

    previous = signal.getsignal(signal.SIGINT)
    replaced = previous is signal.default_int_handler
    if replaced:
        try:
            signal.signal(signal.SIGINT, stop)
        except ValueError:  # not the main interpreter
            replaced = False
    raised = None
    try:
        threading.Thread(target=work, name="indentsim").start()
        while not done.is_set():
            try:
                done.wait()
            except BaseException as e:  # the program's own SIGINT handler raised: stop the call too
                if not isinstance(e, KeyboardInterrupt) and raised is None:
                    raised = e
                interrupted.append(signal.SIGINT)
                _indentsim.request_stop()
    finally:
        if replaced:
            signal.signal(signal.SIGINT, previous)
    if raised is not None:
        raise raised
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"], bool(interrupted)


def _text(value, where):
    """`value`, a str, as the library gets it (UTF-8): refused, naming `where`, when it holds a lone
    surrogate ("\\ud800", or a byte that was not UTF-8 decoded with surrogateescape), which no
    UTF-8 text can hold."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as e:
        raise InputError(f"{where}: {value[e.start]!r} at character {e.start + 1} is a lone surrogate, not text "
                         f"(UTF-8 cannot hold it)") from None
    return value


_INT64 = (-2**63, 2**63 - 1)  # TOML's integers
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key, where):
    """A key (or table name) as TOML text: bare when it can be, else a quoted key."""
    if not isinstance(key, str):
        raise InputError(f"{where}: {key!r}: a key must be a string (got {type(key).__name__})")
    _text(key, f"{where}: key {key!r}")
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key, ensure_ascii=False)


def _toml_value(value, key, where="case"):
    """A Python value as TOML text (floats round-trip through repr).  What TOML cannot hold is
    refused here, naming `where` and the key: never a line and column of the generated text."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        number = int(value)
        if not _INT64[0] <= number <= _INT64[1]:
            digits = str(number)
            shown = digits if len(digits) <= 40 else f"{digits[:12]}... ({len(digits.lstrip('-'))} digits)"
            try:
                hint = f"write it as a float ({float(number)!r})"
            except OverflowError:
                hint = "a float cannot hold it either"
            raise InputError(f"{where}: {key}: the integer {shown} does not fit a 64-bit integer (TOML's); {hint}")
        return str(number)
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (str, os.PathLike)):
        text = os.fspath(value)
        if not isinstance(text, str):
            raise InputError(f"{where}: {key}: a path must be text, not bytes")
        _text(text, f"{where}: {key}")
        # A JSON string is a TOML basic string, but for DEL, which TOML wants escaped.
        return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v, key, where) for v in value) + "]"
    raise InputError(f"{where}: {key}: a value must be a number, a string, a boolean or a list of them "
                     f"(got {type(value).__name__})")


def _case_text(case):
    """A dict in the load-case layout as TOML text."""
    lines = []
    for section, table in case.items():
        name = _toml_key(section, "case")
        if not isinstance(table, dict):
            raise InputError(f"case: {section}: must be a table of keys (a dict), as [{section}] in a "
                             f"load case")
        lines.append(f"[{name}]")
        for key, value in table.items():
            lines.append(f"{_toml_key(key, f'case: {section}')} = {_toml_value(value, f'{section}.{key}')}")
    return "\n".join(lines) + "\n"


def _overrides(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        return [f"{_text(str(key), 'overrides')}={_toml_value(value, key, 'overrides')}"
                for key, value in overrides.items()]
    if isinstance(overrides, str):
        return [_text(overrides, "overrides")]
    return [_text(str(o), "overrides") for o in overrides]


def _names(value, where):
    """A parameter that takes a list of names or files: one (a str or a path) is a list of one,
    never its letters."""
    if value is None:
        return []
    if isinstance(value, (str, os.PathLike)):
        value = [value]
    names = []
    for v in value:
        if not isinstance(v, (str, os.PathLike)) or not isinstance(os.fspath(v), str):
            raise InputError(f"{where}: {v!r}: expects a name or a file (a string), got {type(v).__name__}")
        names.append(_text(os.fspath(v), where))
    return names


def _bounds(bounds):
    """fit()'s bounds: {key: (lower, upper)}, or the CLI's "key=lower:upper" (one, or a list)."""
    if bounds is None:
        return []
    if not isinstance(bounds, dict):
        return _names(bounds, "bounds")
    texts = []
    for key, pair in bounds.items():
        _text(str(key), "bounds")
        try:
            lower, upper = pair
            lower, upper = float(lower), float(upper)
        except (TypeError, ValueError):
            raise InputError(f"bounds: {key}: expects (lower, upper), two numbers (got {pair!r})") from None
        texts.append(f"{key}={lower!r}:{upper!r}")
    return texts


def _case_arguments(case):
    """(file, toml_text, source) of the library's calls."""
    if isinstance(case, dict):
        return "", _case_text(case), "case"
    return os.fspath(case), "", os.fspath(case)


def _read_curve(path):
    """curve.csv as {column: array}; an empty cell (no error estimate there) is NaN."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {name: np.array([float(r[k]) if r[k] != "" else math.nan for r in body])
            for k, name in enumerate(header)}


class Result:
    """A finished run: `curve` (every curve.csv column), `summary` (summary.json), `mesh` (the
    grid lines x, y [m]), `fields` (the final state on the nodes, arrays of shape (nodes_x,
    nodes_y): u, v [m], sigma11, sigma22, sigma12, sigma33 [Pa], strain_intensity), `status`,
    `warnings`, and `write(dir)` for the run's files."""

    def __init__(self, end, folder, temporary):
        self.status = end.status
        self.message = end.message
        self.warnings = list(end.warnings)
        self.folder = folder
        self._temporary = temporary  # removed with this object
        self.curve = _read_curve(os.path.join(folder, "curve.csv"))
        with open(os.path.join(folder, "summary.json")) as f:
            self.summary = json.load(f)
        with open(os.path.join(folder, "case.toml")) as f:
            self.case_toml = f.read()
        self.mesh = {"x": end.x, "y": end.y}
        u, s = end.displacement, end.stress
        names = ("sigma11", "sigma22", "sigma12", "sigma33", "strain_intensity")
        self.fields = {"u": u[:, :, 0], "v": u[:, :, 1], **{n: s[:, :, k] for k, n in enumerate(names)}}

    def write(self, directory):
        """Writes the run's files (curve.csv, summary.json, case.toml, fields, ...; not its
        checkpoints) into `directory`, as a run into that folder would: refused with InputError
        while another run holds the folder (its lock DIR/.indentsim.lock), and an earlier run's
        files there (curve.csv, summary.json, fields.pvd, fields/step_*.vtu,
        checkpoints/checkpoint_*.ck, figures, ...) are removed first; other files are left alone.
        Returns `directory`."""
        directory = os.fspath(directory)
        if os.path.isdir(directory) and os.path.samefile(directory, self.folder):
            return directory

        def copy():
            shutil.copytree(self.folder, directory, dirs_exist_ok=True,
                            ignore=shutil.ignore_patterns(".indentsim.lock", "checkpoints", "*.tmp"))

        _indentsim.write_run_folder(directory, "Result.write", copy)
        try:
            os.rmdir(os.path.join(directory, "checkpoints"))  # made for a run's checkpoints; none are copied
        except OSError:
            pass  # not empty: files that are not a run's
        return directory

    def __repr__(self):
        peak = self.summary.get("peak_force")
        peak = f"{peak:.6g} {self.summary.get('units', {}).get('force', '')}" if peak is not None else "-"
        return f"<indentsim.Result {self.status}: {len(self.curve['step']) - 1} increments, P_max = {peak}>"


def run(case, overrides=None, out=None):
    """Solves a load case (a file, or a dict in the load-case layout) with `overrides`, as
    `indentsim run` does; returns a Result.  The files go to `out` if given, else to a temporary
    folder that lives as long as the Result.  Raises InputError for bad input (nothing solved),
    NotConvergedError (with the converged part as .result) when the solver gives up, and
    RunInterrupted (with the converged part as .result) when Ctrl-C or request_stop() stops it."""
    file, text, source = _case_arguments(case)
    overrides = _overrides(overrides)
    temporary = None
    if out is None:
        temporary = tempfile.TemporaryDirectory(prefix="indentsim_")
        out = temporary.name
    try:
        end, interrupted = _stoppable(_indentsim.run_case, file, text, source, overrides, os.fspath(out))
    except KeyboardInterrupt as e:  # stopped before its first increment (a pilot, the model's set-up)
        raise RunInterrupted(f"{source}: {e}; nothing to resume", None) from None
    result = Result(end, os.fspath(out), temporary)
    if end.status == "stopped":
        kept = " (in a temporary folder, removed with the Result: give run() `out` to keep a run resumable)"
        raise RunInterrupted(f"{end.source}: {end.message}{kept if temporary else ''}", result)
    if interrupted:  # Ctrl-C came as the run ended: the result is whole, and the program stops all the same
        raise RunInterrupted(f"{end.source}: interrupted as the run ended ({end.status}); .result is the whole run",
                             result)
    if end.status == "not_converged":
        raise NotConvergedError(f"{end.source}: {end.message}", result)
    return result


def check(case, overrides=None):
    """Validates a load case and plans its mesh without solving (as `indentsim check`): a dict of
    the model, the mesh size and any plausibility warnings.  Raises InputError."""
    file, text, source = _case_arguments(case)
    return _indentsim.check_case(file, text, source, _overrides(overrides))


def analyze(curve, overrides=None, indenter=None, depth_column="", force_column="", depth_unit="",
            force_unit="", out=None, time_column="", time_unit=""):
    """Oliver-Pharr on every unloading branch of a run (its folder) or of a measured CSV, as
    `indentsim analyze`; returns analysis.json's content (written to `out` if given)."""
    measured = _indentsim.MeasuredCurveOptions()
    measured.indenter_file = os.fspath(indenter) if indenter else ""
    measured.depth_column, measured.force_column = depth_column, force_column
    measured.depth_unit, measured.force_unit = depth_unit, force_unit
    measured.time_column, measured.time_unit = time_column, time_unit
    text = _indentsim.analyze(os.fspath(curve), _overrides(overrides), measured, os.fspath(out) if out else "")
    return json.loads(text)


def fit(input, data=None, free=None, bounds=None, overrides=None, starts=None, out=None,
        finite_differences=False, single_level=False, depth_column="", force_column="", depth_unit="",
        force_unit="", mesh_refinements=None, resume=False, design=True, profile=True, threads=None,
        time_column="", time_unit=""):
    """Material parameters from measured curves, as `indentsim fit`: `input` a load case with
    `data` (a curve file or a list of them) or a fit file; `free` the keys to fit (one key, a list
    of keys, or the CLI's "key,key"); `bounds` {key: (lower, upper)} (or the CLI's
    "key=lower:upper", one or a list); `starts` an integer (default 4); `mesh_refinements` how often
    the forward meshes may be refined where the model's own error moves a parameter more than the
    noise (default 1); `resume` continues the fit stopped in `out` from its fit_checkpoint.json;
    `design=False` skips the table of measurements that would narrow the intervals; `profile=False`
    keeps the linearized intervals (no profile likelihood); `threads` how many starts run side by
    side (default: the cores this process may use; the answer does not depend on it).
    Each parameter of the result has its 95% interval and verdict.  Writes fit.json, fit_curves.csv and
    fitted_case.toml into `out` (or the fit file's [fit] out, else out/fit) and returns fit.json's
    content.  Ctrl-C (or request_stop()) stops it with KeyboardInterrupt."""
    c = _indentsim.FitCommandLine()
    c.input = os.fspath(input)
    c.data_files = _names(data, "data")
    c.free = _names(free, "free")
    c.bounds = _bounds(bounds)
    c.overrides = _overrides(overrides)
    if starts is not None:
        if isinstance(starts, (bool, np.bool_)) or not isinstance(starts, (int, np.integer)):
            raise InputError(f"starts: must be an integer (got {starts!r})")
        c.starts = max(-1, min(int(starts), 1000))  # as a fit file's starts: the library says what is allowed
    if mesh_refinements is not None:
        if isinstance(mesh_refinements, (bool, np.bool_)) or not isinstance(mesh_refinements, (int, np.integer)):
            raise InputError(f"mesh_refinements: must be an integer (got {mesh_refinements!r})")
        c.mesh_refinements = max(-1, min(int(mesh_refinements), 1000))
    if threads is not None:
        if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)):
            raise InputError(f"threads: must be an integer (got {threads!r})")
        c.threads = max(-1, min(int(threads), 100000))
    c.out = os.fspath(out) if out else ""
    c.finite_differences, c.single_level, c.resume = finite_differences, single_level, bool(resume)
    c.no_design, c.no_profile = not design, not profile
    c.depth_column, c.force_column, c.depth_unit, c.force_unit = depth_column, force_column, depth_unit, force_unit
    c.time_column, c.time_unit = time_column, time_unit
    text, interrupted = _stoppable(_indentsim.fit, c)
    if interrupted:
        raise KeyboardInterrupt("the fit ended as Ctrl-C came; its files are written")
    return json.loads(text)
