"""The diskfriction command, in a fresh interpreter (run_cli) or in this one (run_main), and
what its stderr may hold when it fails (error_line).

run_main is for bad input: a refusal comes before any work, so what a fresh interpreter adds
(its start and imports, 1-2 s a command) tests nothing there. run_cli is for what needs a fresh
interpreter: `python -m diskfriction` itself, signals, kernel and compile caches, environment
variables read at import, and one refusal per command family, end to end."""
from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
import traceback
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

DEFAULT_IGNORED = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)
"""The warning categories a fresh interpreter ignores (Python's default filters); every other
warning it shows once per place, on stderr."""


def run_cli(*args: str, cwd: Path = ROOT, timeout: float = 300,
            env: dict | None = None) -> subprocess.CompletedProcess:
    """``python -m diskfriction ARGS`` (stderr is a pipe: progress is one line per stage)."""
    return subprocess.run([sys.executable, "-m", "diskfriction", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          env=os.environ | (env or {}))


def run_main(*args: str, cwd: Path = ROOT, env: dict | None = None) -> subprocess.CompletedProcess:
    """``diskfriction ARGS`` in this interpreter: cli.main.main(list(args)) in `cwd`, with `env`
    added to os.environ, as run_cli runs it, and the same CompletedProcess (args, returncode,
    stdout, stderr), for error_line and the same assertions.

    stdout and stderr are strings that are not terminals (as run_cli's pipes: progress is one
    line per stage). The exit code is what the interpreter would exit with: main's return; a
    SystemExit's code (argparse's usage errors and --help, exit 2 and 0; None is 0, a message
    goes to stderr with 1); any other exception its traceback on stderr and 1. Warnings are
    shown on stderr as a fresh interpreter shows them (DEFAULT_IGNORED left out), not kept by
    pytest. The working directory, os.environ and the warning filters are restored afterwards,
    whatever the command changed. A KeyboardInterrupt that main() lets through (not the
    command's own Ctrl-C, which main turns into exit 130 and one line) is raised: it is the
    test run's."""
    out, err = io.StringIO(), io.StringIO()
    before_env, before_cwd = dict(os.environ), os.getcwd()
    try:
        os.environ.update(env or {})
        os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                warnings.catch_warnings():
            warnings.resetwarnings()
            warnings.simplefilter("default")
            for category in DEFAULT_IGNORED:
                warnings.simplefilter("ignore", category)
            warnings.showwarning = shown_on_stderr
            try:
                from diskfriction.cli.main import main

                code = main(list(args))
            except SystemExit as exit:
                code = exit_code(exit.code)
            except Exception:  # noqa: BLE001 - as the interpreter: the traceback and exit 1
                traceback.print_exc(file=sys.stderr)
                code = 1
    finally:
        os.chdir(before_cwd)
        for name in set(os.environ) - set(before_env):
            del os.environ[name]
        os.environ.update(before_env)
    return subprocess.CompletedProcess(["diskfriction", *args], code, out.getvalue(), err.getvalue())


def exit_code(code) -> int:
    """The exit status of ``raise SystemExit(code)``, as the interpreter ends: None is 0, an
    integer itself, anything else is printed on stderr and gives 1."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code
    print(code, file=sys.stderr)
    return 1


def shown_on_stderr(message, category, filename, lineno, file=None, line=None) -> None:
    """warnings.showwarning as the interpreter's: the formatted warning on (redirected) stderr."""
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def error_line(result: subprocess.CompletedProcess, command: str) -> str:
    """The one error line of a failed command: the last line of stderr; every line before it
    is a progress line ("COMMAND: stage"); no traceback anywhere."""
    lines = result.stderr.splitlines()
    assert lines and "Traceback" not in result.stderr + result.stdout, result.stderr
    assert all(line.startswith(f"{command}: ") for line in lines[:-1]), result.stderr
    assert lines[-1].startswith(f"{command} error: "), result.stderr
    return lines[-1]
