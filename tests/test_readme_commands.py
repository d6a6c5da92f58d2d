#!/usr/bin/env python3
"""Runs the README's commands, as written, and checks that each one succeeds.

    python3 tests/test_readme_commands.py <path-to-indentsim-cli> <source-dir>

Every fenced shell block of README.md (```sh, ```bash, ```shell, ```console) is read in order.
A command that invokes `indentsim` or `./build/indentsim` with one of the subcommands run,
resume, check, plot, analyze, fit or sweep is run, and so is a file written by a here-document
(`cat > FILE <<'EOF'` ... `EOF`) that later commands read; lines of `./scripts/*.sh` (install,
build) are skipped, and so is anything else. Lines joined by a trailing backslash are one command.

The commands run in README order in one fresh temporary folder, the project root's stand-in: the
source tree's top-level entries (loadcases, examples, plots, ...) are symlinked into it,
`build/indentsim` points to the given CLI, and `build/` leads the PATH, so `indentsim` alone
works too. Outputs go into the temporary folder, never into the source tree. Commands that read
what an earlier one wrote (a plot of a run's folder) therefore find it.

To keep the whole script well under two minutes, a small mesh is appended where a command solves
a case and accepts load-case overrides: `--set mesh.contact_nodes=8` on run, check and fit (the
key is looked up in `indentsim keys` first; a command that sets it itself is left alone). resume
refuses mesh changes, analyze takes only analysis keys, and plot and sweep have no --set: they run
exactly as written.

Each command must exit with status 0. Prints one line per command, then `N passed, N failed`;
exits 1 if any failed (or if README.md holds no such command at all).
"""
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile
import time

SUBCOMMANDS = ("run", "resume", "check", "plot", "analyze", "fit", "sweep")
INDENTSIM = re.compile(r"(?:^|[\s;&|(])(?:\./build/indentsim|indentsim)\s+(" + "|".join(SUBCOMMANDS) + r")\b")
HEREDOC = re.compile(r"<<-?\s*(['\"]?)([A-Za-z_][A-Za-z0-9_]*)\1")
FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})\s*([A-Za-z0-9_+-]*)")
SHELL_LANGUAGES = {"sh", "bash", "shell", "console", "zsh"}
SMALL_MESH_KEY = "mesh.contact_nodes"
SMALL_MESH_VALUE = "8"
TAKES_MESH_OVERRIDE = {"run", "check", "fit"}
TIMEOUT_S = 600


def fenced_shell_blocks(text):
    """The lines of every fenced shell block, in order: a list of (first line number, lines)."""
    blocks = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, language = m.group(2), m.group(3).lower()
        start = i + 1
        j = start
        while j < len(lines) and not lines[j].strip().startswith(fence):
            j += 1
        if language in SHELL_LANGUAGES:
            blocks.append((start + 1, lines[start:j]))
        i = j + 1
    return blocks


def commands_of(block_start, lines):
    """Shell commands of one block: continuation lines joined, here-documents kept whole."""
    commands = []
    i = 0
    while i < len(lines):
        line_number = block_start + i
        line = lines[i]
        if line.lstrip().startswith("$ "):  # a console prompt
            line = line.lstrip()[2:]
        while line.rstrip().endswith("\\") and i + 1 < len(lines):
            i += 1
            line = line.rstrip()[:-1] + " " + lines[i].strip()
        i += 1
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        heredoc = HEREDOC.search(line)
        if heredoc:
            terminator = heredoc.group(2)
            body = []
            while i < len(lines) and lines[i].strip() != terminator:
                body.append(lines[i])
                i += 1
            i += 1  # the terminator
            line = "\n".join([line] + body + [terminator])
        commands.append((line_number, line))
    return commands


def classify(command):
    """'case' (an indentsim subcommand), 'file' (a here-document), 'script' or 'other'."""
    first = command.splitlines()[0].strip()
    if re.match(r"^(?:bash\s+|sh\s+)?\./scripts/\S+\.sh\b", first):
        return "script", None
    m = INDENTSIM.search(first)
    if m and "<<" not in first:
        return "case", m.group(1)
    if HEREDOC.search(first) and re.match(r"^cat\s*>", first):
        return "file", None
    return "other", None


def with_small_mesh(command, subcommand, mesh_key_known):
    """The command with the small mesh appended where its subcommand takes it."""
    if subcommand not in TAKES_MESH_OVERRIDE or not mesh_key_known:
        return command
    words = shlex.split(command, comments=True)
    if any(w.startswith(SMALL_MESH_KEY + "=") for w in words):
        return command
    return " ".join(shlex.quote(w) for w in words + ["--set", f"{SMALL_MESH_KEY}={SMALL_MESH_VALUE}"])


def prepare_root(tmp, cli, source):
    """tmp as a stand-in for the project root: the sources symlinked, build/indentsim the CLI."""
    for entry in sorted(source.iterdir()):
        if entry.name in ("build", "out", ".git") or entry.name.startswith("."):
            continue
        (tmp / entry.name).symlink_to(entry)
    (tmp / "build").mkdir()
    (tmp / "build" / "indentsim").symlink_to(cli)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    cli = pathlib.Path(sys.argv[1]).resolve()
    source = pathlib.Path(sys.argv[2]).resolve()
    readme = source / "README.md"
    if not cli.is_file() or not os.access(cli, os.X_OK):
        print(f"{cli}: not an executable", file=sys.stderr)
        return 2
    if not readme.is_file():
        print(f"{readme}: not a file", file=sys.stderr)
        return 2

    keys = subprocess.run([str(cli), "keys"], capture_output=True, text=True)
    mesh_key_known = keys.returncode == 0 and re.search(r"(^|\s)" + re.escape(SMALL_MESH_KEY) + r"\b", keys.stdout)
    if not mesh_key_known:
        print(f"note: `indentsim keys` does not list {SMALL_MESH_KEY}; running the cases at their own meshes")

    commands = []
    for start, lines in fenced_shell_blocks(readme.read_text(encoding="utf-8")):
        commands.extend(commands_of(start, lines))

    passed, failures = 0, []
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="indentsim_readme_") as name:
        tmp = pathlib.Path(name)
        prepare_root(tmp, cli, source)
        environment = dict(os.environ, PATH=f"{tmp / 'build'}{os.pathsep}{os.environ.get('PATH', '')}")
        for line_number, command in commands:
            kind, subcommand = classify(command)
            shown = command.splitlines()[0]
            if kind in ("script", "other"):
                print(f"skipped   README.md:{line_number}: {shown}")
                continue
            to_run = with_small_mesh(command, subcommand, mesh_key_known) if kind == "case" else command
            t0 = time.monotonic()
            try:
                result = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", to_run], cwd=tmp, env=environment,
                                        capture_output=True, text=True, timeout=TIMEOUT_S)
                status, stderr = result.returncode, result.stderr
            except subprocess.TimeoutExpired:
                status, stderr = None, f"timed out after {TIMEOUT_S} s"
            seconds = time.monotonic() - t0
            if status == 0:
                passed += 1
                print(f"passed    README.md:{line_number}: {shown}  ({seconds:.1f} s)")
            else:
                failures.append(line_number)
                print(f"FAILED    README.md:{line_number}: {shown}  (exit {status}, {seconds:.1f} s)")
                if to_run != command:
                    print(f"          as run: {to_run}")
                for err_line in stderr.strip().splitlines()[-15:]:
                    print(f"          | {err_line}")
    if passed + len(failures) == 0:
        print("README.md holds no fenced shell command that runs indentsim")
        failures.append(0)
    print(f"total {time.monotonic() - started:.1f} s")
    print(f"{passed} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
