#!/usr/bin/env python3
"""Behaviour kept bit for bit across a refactor: every shipped case's outputs, compared.

  same_outputs.py run CLI OUT        runs every loadcases/**/*.toml with CLI into OUT/<case>
  same_outputs.py compare A B CLI    compares two such trees, and resumes A's checkpoints with CLI
                                     (B's build); exit 1 on any difference

What must be identical (issue 36): curve.csv in every column but the wall time; summary.json in
every number but its timings (and the build's commit string; B may add members); case.toml but for output.dir and the build's line;
layers.csv, profiles.csv, the VTU fields and fields.pvd byte for byte.  Checkpoints record the
run folder's path and each row's wall time, so they are checked by what they do: `compare` resumes
the middle checkpoint of every case of A with B's CLI and asks for A's curve and summary again).
Run it before and after a refactor with the two builds:

  python3 benchmarks/same_outputs.py run OLD/indentsim /tmp/before
  python3 benchmarks/same_outputs.py run build/indentsim /tmp/after
  python3 benchmarks/same_outputs.py compare /tmp/before /tmp/after build/indentsim
"""
import csv
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

SOURCE = pathlib.Path(__file__).resolve().parent.parent
TIMING_COLUMNS = {"wall_s"}
# summary.json keys whose values are measured times or ratios of times, or name the build.
TIMING_KEYS = {"time_s", "wall_added_s", "wall_fraction", "cost_fraction", "indentsim"}


def shipped_cases():
    return sorted(p for p in (SOURCE / "loadcases").rglob("*.toml"))


def run(cli, out):
    out = pathlib.Path(out)
    for case in shipped_cases():
        rel = case.relative_to(SOURCE / "loadcases").with_suffix("")
        dest = out / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run([cli, "run", str(case), "--out", str(dest)], capture_output=True, text=True)
        # A case that is refused or fails must fail the same way in both builds: keep its words
        # (but the progress lines, which carry the elapsed time).
        words = [l for l in proc.stderr.splitlines() if not (l.startswith("increment ") and "elapsed" in l)]
        (out / (str(rel).replace("/", "__") + ".exit")).write_text("\n".join([str(proc.returncode)] + words))
        print(f"{rel}: exit {proc.returncode}")
    return 0


def without_timings(value):
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def holds(a, b):
    """B holds everything A says, with the same values (B may say more: a new member)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and all(k in b and holds(v, b[k]) for k, v in a.items())
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(holds(x, y) for x, y in zip(a, b))
    return a == b


def compare_curve(a, b):
    with open(a, newline="") as fa, open(b, newline="") as fb:
        ra, rb = list(csv.DictReader(fa)), list(csv.DictReader(fb))
    if len(ra) != len(rb):
        return f"{len(ra)} rows against {len(rb)}"
    for i, (x, y) in enumerate(zip(ra, rb)):
        if x.keys() != y.keys():
            return "columns differ"
        for k in x:
            if k not in TIMING_COLUMNS and x[k] != y[k]:
                return f"row {i} column {k}: {x[k]} against {y[k]}"
    return None


def compare_run(pa, pb):
    """Differences between two run folders' curve.csv and summary.json, or None."""
    why = compare_curve(pa / "curve.csv", pb / "curve.csv")
    if why:
        return f"curve.csv: {why}"
    ja, jb = (without_timings(json.loads((p / "summary.json").read_text())) for p in (pa, pb))
    return None if holds(ja, jb) else "summary.json: numbers differ"


def resume_checkpoints(a, cli):
    """Resumes the middle checkpoint of every run in A with CLI: the same curve and summary."""
    problems = []
    for summary in sorted(a.rglob("summary.json")):
        run_dir = summary.parent
        checkpoints = sorted((run_dir / "checkpoints").glob("*.ck"))
        if len(checkpoints) < 2:
            continue
        middle = checkpoints[len(checkpoints) // 2 - 1]
        dest = pathlib.Path(tempfile.mkdtemp()) / "resumed"
        proc = subprocess.run([cli, "resume", str(middle), "--out", str(dest)], capture_output=True, text=True)
        why = f"exit {proc.returncode}: {proc.stderr.strip()[:200]}" if proc.returncode else compare_run(run_dir, dest)
        shutil.rmtree(dest.parent, ignore_errors=True)
        if why:
            problems.append(f"{middle.relative_to(a)} resumed: {why}")
    return problems


def compare(a, b, cli):
    a, b = pathlib.Path(a), pathlib.Path(b)
    files_a = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    files_b = sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    problems = []
    if files_a != files_b:
        problems.append(f"file lists differ: only in A {sorted(set(files_a) - set(files_b))[:5]}, "
                        f"only in B {sorted(set(files_b) - set(files_a))[:5]}")
    for rel in sorted(set(files_a) & set(files_b)):
        pa, pb = a / rel, b / rel
        if rel.name == ".indentsim.lock" or rel.suffix == ".ck":
            continue
        if rel.name == "curve.csv":
            why = compare_curve(pa, pb)
        elif rel.name == "summary.json":
            ja, jb = (without_timings(json.loads(p.read_text())) for p in (pa, pb))
            why = None if holds(ja, jb) else "numbers differ"
        elif rel.name == "case.toml":
            la, lb = ([l for l in p.read_text().splitlines() if not l.startswith(("dir = ", "# Written by"))]
                      for p in (pa, pb))
            why = None if la == lb else "differs"
        else:
            why = None if pa.read_bytes() == pb.read_bytes() else "bytes differ"
        if why:
            problems.append(f"{rel}: {why}")
    problems += resume_checkpoints(a, cli)
    for p in problems:
        print(p)
    print(f"{len(set(files_a) & set(files_b))} files compared and checkpoints resumed, {len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "run":
        sys.exit(run(sys.argv[2], sys.argv[3]))
    if len(sys.argv) == 5 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3], sys.argv[4]))
    print(__doc__)
    sys.exit(2)
