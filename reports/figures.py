"""What every figure shares: an Agg canvas, saving, legends, the Re-axis scale, event marks
and the three outcomes of a run (slid, stayed, not resolved).

Plots only: no physics.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.files import write_atomic

DPI = 110

SLID_WORDS = {True: "yes", False: "no", None: "not resolved"}
"""A run's `slid` in words: None where its energy budget did not close (accurate false;
dynamics/simulate.py summarize), so whether it slid is not known."""
OUTCOME_STYLE = {True: dict(color="C3", alpha=0.30, hatch=None),
                 False: dict(color="C0", alpha=0.18, hatch=None),
                 None: dict(color="0.5", alpha=0.25, hatch="xx")}
"""Shading of a window whose run slid (red), stayed (blue) or is not resolved (grey, hatched)."""
OUTCOME_LABELS = {True: "run slid", False: "run stayed (did not slide)",
                  None: "run not resolved (energy budget did not close)"}
EVENTS = {"first_breach": ("C3", "--", "first Coulomb breach (any disk)"),
          "onset": ("C2", "-.", "first onset of sliding (any disk)")}
"""Colour, line style and legend label of the vertical line at a run's first event."""


def slid_word(slid: Optional[bool]) -> str:
    """'yes', 'no' or 'not resolved' (slid None)."""
    return SLID_WORDS[None if slid is None else bool(slid)]


def outcome_word(slid: Optional[bool]) -> str:
    """'slid', 'stayed' or 'not resolved' (slid None)."""
    return {True: "slid", False: "stayed", None: "not resolved"}[None if slid is None else bool(slid)]


def new_figure(nrows: int = 1, ncols: int = 1, *, figsize=None, **kwargs):
    """(figure, axes) as matplotlib.pyplot.subplots(nrows, ncols, figsize=..., **kwargs) gives
    them, at DPI, on an Agg canvas of its own: the one place a figure starts. pyplot is not
    imported (its figure registry and backend selection are of no use to a file written once:
    0.03-0.06 s of a command's start)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=DPI)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def save_figure(fig, path: Path) -> None:
    """Write `fig` atomically as PNG at DPI: the one place a figure is saved (nothing to close:
    no pyplot registry holds it)."""
    write_atomic(Path(path), lambda tmp: fig.savefig(tmp, dpi=DPI, format="png"))


def legend(ax, handles: list, **kwargs):
    """ax.legend of `handles`, where a tuple of lines is drawn as its lines side by side (a
    line kind drawn in several colours shows several of them)."""
    from matplotlib.legend_handler import HandlerTuple

    return ax.legend(handles=handles, labels=[handle_label(h) for h in handles],
                     handler_map={tuple: HandlerTuple(ndivide=None, pad=0.0)}, **kwargs)


def line_key(colors: list, style: str, label: str, width: float = 1.0) -> tuple:
    """A legend entry for lines drawn in `colors` (up to three shown) with line style `style`;
    its label is set on the first segment, which legend() reads for the tuple."""
    from matplotlib.lines import Line2D

    from matplotlib.colors import to_hex

    shown = list(dict.fromkeys(to_hex(c, keep_alpha=True) for c in colors))[:3] or ["k"]
    lines = tuple(Line2D([], [], color=c, ls=style, lw=width) for c in shown)
    lines[0].set_label(label)
    return lines


def handle_label(handle) -> str:
    """The label of a legend handle (a tuple's first member's)."""
    return (handle[0] if isinstance(handle, tuple) else handle).get_label()


def relabel(handle, label: str) -> None:
    """Set the label of a legend handle (a tuple's first member's)."""
    (handle[0] if isinstance(handle, tuple) else handle).set_label(label)


RE_TINY = 1e-9
"""|Re| below RE_TINY times the largest counts as zero when the scale is chosen (rounding of
a zero eigenvalue, e.g. a free rolling mode)."""
LOG_DECADES = 2.0
"""Re spanning more than this many decades (all of one sign) is drawn on a log axis."""


def re_scale(values: np.ndarray) -> str:
    """The Re axis for these values: "log" when the nonzero finite values are all positive
    and span more than LOG_DECADES decades, "-log" (log of -Re) when all negative and as wide,
    else "linear". A log axis shows every decade without the false kink a symlog axis makes
    where its linear core meets the log part; values of both signs are drawn linearly."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    big = float(np.max(np.abs(v), initial=0.0))
    v = v[np.abs(v) > RE_TINY * big]
    if not v.size or (v.min() < 0 < v.max()):
        return "linear"
    decades = np.log10(np.abs(v).max() / np.abs(v).min())
    if decades <= LOG_DECADES:
        return "linear"
    return "log" if v.min() > 0 else "-log"


def re_values(values: np.ndarray, scale: str) -> np.ndarray:
    """What the Re axis plots: -Re for "-log", else Re."""
    return -np.asarray(values) if scale == "-log" else np.asarray(values)


def set_re_axis(ax, values: np.ndarray, scale: str, label: str) -> None:
    """Log (for "log" and "-log") or linear y axis with its label ("-" prefixed for -log);
    on a log axis the lower limit is the smallest positive value drawn, less a margin."""
    if scale == "linear":
        ax.set_yscale("linear")
        ax.set_ylabel(label)
        return
    v = re_values(values, scale)
    v = v[np.isfinite(v) & (v > RE_TINY * np.nanmax(np.abs(v)))]
    ax.set_yscale("log")
    ax.set_ylim(v.min() / 1.5, v.max() * 1.5)
    ax.set_ylabel(("$-$" + label) if scale == "-log" else label)


def mark_events(ax, times: dict, scale: float = 1.0) -> list:
    """A vertical line at each event time given (EVENTS' keys -> time or None, divided by
    `scale`); returns the legend handles of the lines drawn."""
    from matplotlib.lines import Line2D

    handles = []
    for event, when in times.items():
        if when is None or not np.isfinite(when):
            continue
        color, style, label = EVENTS[event]
        ax.axvline(when / scale, color=color, ls=style, lw=0.9)
        handles.append(Line2D([], [], color=color, ls=style, lw=0.9, label=label))
    return handles


def first_event(summary: dict, event: str) -> float | None:
    """Earliest time any disk had `event` ("first_breach" or "onset") [raw time], or None."""
    times = [t for t in summary[event]["t"] if t is not None]
    return min(times) if times else None


def outcome_patches() -> list:
    """Legend patches of the three outcomes of a run (OUTCOME_STYLE)."""
    from matplotlib.patches import Patch

    return [Patch(facecolor=OUTCOME_STYLE[k]["color"], alpha=OUTCOME_STYLE[k]["alpha"] + 0.15,
                  hatch=OUTCOME_STYLE[k]["hatch"], label=OUTCOME_LABELS[k])
            for k in (True, False, None)]


LABEL_OFFSETS = ((4, 3), (4, -9), (-4, 3), (-4, -9))
"""Where a point's label may go, in points from it (right-up, right-down, left-up, left-down)."""


def readable_log_axis(axis) -> None:
    """A log axis (wall times) labelled in plain numbers at 1, 2 and 5 x 10^k where its data
    span less than two decades, at the decades otherwise, its minor ticks unlabelled:
    matplotlib's default labels every minor tick of an axis within a decade in 'a x 10^k'
    form, and the labels run into each other. Call once the data are plotted."""
    from matplotlib.ticker import LogLocator, NullFormatter, StrMethodFormatter

    lo, hi = sorted(axis.get_data_interval())
    decades = np.log10(hi / lo) if lo > 0 else np.inf
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0) if decades < 2 else (1.0,)))
    axis.set_major_formatter(StrMethodFormatter("{x:g}"))
    axis.set_minor_formatter(NullFormatter())


LABEL_GAP = 2.0
"""Display pixels kept free around a point label, so that two labels never touch."""


def label_points(ax, xs, ys, texts, fontsize: float = 6) -> int:
    """Label each point (x, y) with its text at the first of LABEL_OFFSETS where the label
    (padded by LABEL_GAP) overlaps no text already on the axes, this call's labels or an
    earlier call's (another series); a label that fits nowhere is left out (the caller's table lists every value). Call once the axes' limits are final. Returns
    how many were left out."""
    ax.autoscale_view()  # the limits are otherwise settled only when drawn
    renderer = ax.figure.canvas.get_renderer()
    placed = [text.get_window_extent(renderer).padded(LABEL_GAP) for text in ax.texts]
    left_out = 0
    for x, y, text in zip(xs, ys, texts):
        for dx, dy in LABEL_OFFSETS:
            label = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points",
                                fontsize=fontsize, ha="left" if dx > 0 else "right")
            box = label.get_window_extent(renderer).padded(LABEL_GAP)
            if not any(box.overlaps(other) for other in placed):
                placed.append(box)
                break
            label.remove()
        else:
            left_out += 1
    return left_out
