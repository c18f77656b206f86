"""Progress of a command on stderr: the one place that draws it.

A command goes through stages (kernel generation, compilation, a sweep, runs, plotting,
writing). On a terminal the current stage is one status line, with a bar while the stage
reports fractions (redrawn at most every 0.1 s), cleared when the command ends. Anywhere else
(a pipe, a log file) each stage prints one line when it starts, ``COMMAND: STAGE``, and
nothing per step, so a log shows what the time went into.

    progress = Progress("bifurcate")
    system = System.from_scene(scene, progress.part("kernels"))  # lower layers report
    progress.stage("sweep F_x 0 -> 0.12")                         # (stage, fraction)
    progress(0.4, "F_x = 0.048")                                  # the current stage's bar
    progress.close()
"""
from __future__ import annotations

import sys
import time
from typing import Callable, Optional

REDRAW = 0.1
"""Seconds between redraws of a bar."""


class Progress:
    """Stages and bars of one command on `stream` (default stderr); see the module docstring."""

    def __init__(self, command: str, width: int = 30, stream=None) -> None:
        self.command, self.width = command, width
        self.stream = stream or sys.stderr
        self.terminal = self.stream.isatty()
        self.current: Optional[str] = None
        self._last = 0.0

    def _draw(self, text: str) -> None:
        self.stream.write(f"\r{text}\x1b[K")
        self.stream.flush()

    def stage(self, name: str) -> None:
        """Start stage `name` (nothing if it is the current one)."""
        if name == self.current:
            return
        self.current, self._last = name, 0.0
        if self.terminal:
            self._draw(f"{self.command}: {name}")
        else:
            print(f"{self.command}: {name}", file=self.stream, flush=True)

    def __call__(self, fraction: float, note: str = "") -> None:
        """The current stage's bar at `fraction` (0..1) with a note; drawn on a terminal only."""
        now = time.monotonic()
        if not self.terminal or now - self._last < REDRAW:
            return
        self._last = now
        fraction = min(max(fraction, 0.0), 1.0)
        filled = int(round(self.width * fraction))
        self._draw(f"{self.command}: {self.current} [{'#' * filled}{'.' * (self.width - filled)}] "
                   f"{100 * fraction:5.1f}% {note}")

    def part(self, name: str) -> Callable[[str, Optional[float]], None]:
        """The callback lower layers take, progress(stage, fraction or None), shown as the
        stages "NAME: stage" of this command."""

        def report(stage: str, fraction: Optional[float] = None) -> None:
            self.stage(f"{name}: {stage}")
            if fraction is not None:
                self(fraction)

        return report

    def close(self) -> None:
        """End: on a terminal the status line is cleared, so only the results remain."""
        if self.terminal and self.current is not None:
            self._draw("")
        self.current = None
