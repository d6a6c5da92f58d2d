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

Sweeps over many cases, on this machine or a Dask cluster: indentsim.sweep (sweep.py).
"""
import csv
import json
import math
import os
import shutil
import tempfile

import numpy as np

from . import _indentsim
from ._indentsim import InputError, IoError, SolverError

__all__ = ["run", "check", "analyze", "fit", "Result", "InputError", "IoError", "SolverError",
           "NotConvergedError", "version"]


def version():
    """The library's version line (as `indentsim --version`)."""
    return _indentsim.version()


class NotConvergedError(RuntimeError):
    """The solver could not converge (the CLI's exit status 3).  `.result` holds the converged
    increments, as the CLI keeps them."""

    def __init__(self, message, result):
        super().__init__(message)
        self.result = result


def _toml_value(value, key):
    """A Python value as TOML text (floats round-trip through repr)."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (str, os.PathLike)):
        return json.dumps(os.fspath(value), ensure_ascii=False)  # a JSON string is a TOML basic string
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v, key) for v in value) + "]"
    raise InputError(f"case: {key}: a value must be a number, a string, a boolean or a list of them "
                     f"(got {type(value).__name__})")


def _case_text(case):
    """A dict in the load-case layout as TOML text."""
    lines = []
    for section, table in case.items():
        if not isinstance(table, dict):
            raise InputError(f"case: {section}: must be a table of keys (a dict), as [{section}] in a "
                             f"load case")
        lines.append(f"[{section}]")
        lines += [f"{key} = {_toml_value(value, f'{section}.{key}')}" for key, value in table.items()]
    return "\n".join(lines) + "\n"


def _overrides(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        return [f"{key}={_toml_value(value, key)}" for key, value in overrides.items()]
    if isinstance(overrides, str):
        return [overrides]
    return [str(o) for o in overrides]


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
        """Copies the run's files (curve.csv, summary.json, case.toml, fields, ...) into `directory`."""
        directory = os.fspath(directory)
        if os.path.abspath(directory) == os.path.abspath(self.folder):
            return directory
        shutil.copytree(self.folder, directory, dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns(".indentsim.lock", "checkpoints"))
        return directory

    def __repr__(self):
        peak = self.summary.get("peak_force")
        peak = f"{peak:.6g} {self.summary.get('units', {}).get('force', '')}" if peak is not None else "-"
        return f"<indentsim.Result {self.status}: {len(self.curve['step']) - 1} increments, P_max = {peak}>"


def run(case, overrides=None, out=None):
    """Solves a load case (a file, or a dict in the load-case layout) with `overrides`, as
    `indentsim run` does; returns a Result.  The files go to `out` if given, else to a temporary
    folder that lives as long as the Result.  Raises InputError for bad input (nothing solved),
    NotConvergedError (with the converged part as .result) when the solver gives up."""
    file, text, source = _case_arguments(case)
    temporary = None
    if out is None:
        temporary = tempfile.TemporaryDirectory(prefix="indentsim_")
        out = temporary.name
    end = _indentsim.run_case(file, text, source, _overrides(overrides), os.fspath(out))
    result = Result(end, os.fspath(out), temporary)
    if end.status == "not_converged":
        raise NotConvergedError(f"{end.source}: {end.message}", result)
    return result


def check(case, overrides=None):
    """Validates a load case and plans its mesh without solving (as `indentsim check`): a dict of
    the model, the mesh size and any plausibility warnings.  Raises InputError."""
    file, text, source = _case_arguments(case)
    return _indentsim.check_case(file, text, source, _overrides(overrides))


def analyze(curve, overrides=None, indenter=None, depth_column="", force_column="", depth_unit="",
            force_unit="", out=None):
    """Oliver-Pharr on every unloading branch of a run (its folder) or of a measured CSV, as
    `indentsim analyze`; returns analysis.json's content (written to `out` if given)."""
    measured = _indentsim.MeasuredCurveOptions()
    measured.indenter_file = os.fspath(indenter) if indenter else ""
    measured.depth_column, measured.force_column = depth_column, force_column
    measured.depth_unit, measured.force_unit = depth_unit, force_unit
    text = _indentsim.analyze(os.fspath(curve), _overrides(overrides), measured, os.fspath(out) if out else "")
    return json.loads(text)


def fit(input, data=None, free=None, bounds=None, overrides=None, starts=None, out=None,
        finite_differences=False, single_level=False, depth_column="", force_column="", depth_unit="",
        force_unit=""):
    """Material parameters from measured curves, as `indentsim fit`: `input` a load case with
    `data` (a curve file or a list of them) or a fit file; `free` the keys to fit; `bounds`
    {key: (lower, upper)}.  Writes fit.json, fit_curves.csv and fitted_case.toml into `out` (or
    the fit file's [fit] out, else out/fit) and returns fit.json's content."""
    c = _indentsim.FitCommandLine()
    c.input = os.fspath(input)
    c.data_files = [os.fspath(data)] if isinstance(data, (str, os.PathLike)) else [os.fspath(d) for d in data or []]
    c.free = list(free or [])
    c.bounds = [f"{k}={float(lo)!r}:{float(hi)!r}" for k, (lo, hi) in (bounds or {}).items()]
    c.overrides = _overrides(overrides)
    c.starts = starts
    c.out = os.fspath(out) if out else ""
    c.finite_differences, c.single_level = finite_differences, single_level
    c.depth_column, c.force_column, c.depth_unit, c.force_unit = depth_column, force_column, depth_unit, force_unit
    return json.loads(_indentsim.fit(c))
