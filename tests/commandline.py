"""The diskfriction command in a fresh interpreter, and what its stderr may hold when it fails."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args: str, cwd: Path = ROOT, timeout: float = 300,
            env: dict | None = None) -> subprocess.CompletedProcess:
    """``python -m diskfriction ARGS`` (stderr is a pipe: progress is one line per stage)."""
    return subprocess.run([sys.executable, "-m", "diskfriction", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          env=os.environ | (env or {}))


def error_line(result: subprocess.CompletedProcess, command: str) -> str:
    """The one error line of a failed command: the last line of stderr; every line before it
    is a progress line ("COMMAND: stage"); no traceback anywhere."""
    lines = result.stderr.splitlines()
    assert lines and "Traceback" not in result.stderr + result.stdout, result.stderr
    assert all(line.startswith(f"{command}: ") for line in lines[:-1]), result.stderr
    assert lines[-1].startswith(f"{command} error: "), result.stderr
    return lines[-1]
