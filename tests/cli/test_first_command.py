"""What keeps the README's first command quick (issue 60 item 18): the diagram draws few
artists and needs no pyplot, and the program does not spend its exit in the garbage collector."""
from __future__ import annotations

import gc
import subprocess
import sys

import numpy as np


def test_the_diagram_draws_one_marker_line_per_kind_and_panel():
    """Births, deaths and narrow bubbles are one line of markers each per panel, not one
    artist per collision (22 collisions of the paper's scene made 44 lines)."""
    from matplotlib.figure import Figure

    from diskfriction.reports.bifurcation import BIRTH, BUBBLE, DEATH, draw_spectrum

    F = np.linspace(0.0, 1.0, 41)
    im = np.where((F > 0.2) & (F < 0.8), 1e-3 * np.sin(np.pi * (F - 0.2) / 0.6), 0.0)
    re = 0.05 + 0.01 * F
    lam = np.column_stack([re + 1j * im, re - 1j * im, 0.01 + 0.1 * F + 0j])
    collisions = [(0.2, "birth", 0.052), (0.5, "birth", 0.055), (0.5 + 1e-9, "death", 0.055),
                  (0.8, "death", 0.058), (0.9, "birth", 0.1), (0.95, "death", 0.1)]
    top, bottom = Figure().subplots(2, 1)
    draw_spectrum(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int), collisions,
                  "J", re_axis="linear")
    for ax in (top, bottom):
        marks = {(line.get_marker(), line.get_color()): line.get_xdata() for line in ax.lines}
        assert len(ax.lines) == 3
        assert list(marks[BIRTH]) == [0.2, 0.9] and list(marks[DEATH]) == [0.8, 0.95]
        assert list(marks[BUBBLE]) == [0.5 + 5e-10]


def test_figures_start_and_are_saved_without_pyplot(tmp_path):
    """reports.figures.new_figure and save_figure on an Agg canvas of their own: importing
    pyplot cost the diagram 0.03-0.06 s."""
    code = ("import sys; from diskfriction.reports.figures import new_figure, save_figure; "
            "fig, ax = new_figure(figsize=(2, 1)); ax.plot([0, 1], [1, 0]); "
            f"save_figure(fig, {str(tmp_path / 'f.png')!r}); "
            "print('matplotlib.pyplot' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_program_freezes_what_it_made_before_it_exits(monkeypatch, capsys):
    """main() run as the program (no argv) leaves every object frozen: the interpreter's last
    collections walked them all, 0.8-1.4 s of the first command between its return and its
    exit. Called with argv (a test, a caller), it freezes nothing."""
    from diskfriction.cli.main import main

    gc.unfreeze()
    try:
        assert main(["scene"]) == 0 and gc.get_freeze_count() == 0
        monkeypatch.setattr(sys, "argv", ["diskfriction", "scene"])
        assert main() == 0 and gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()
    assert 'name = "paper"' in capsys.readouterr().out
