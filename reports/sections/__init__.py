"""The report's sections in order; `--only KEY` picks some of them."""
from diskfriction.reports.sections import (accuracy, condition, fig2, fig5, fig6, lammps, paper,
                                          readings, runs)

SECTIONS = (fig2.SECTION, condition.SECTION, runs.FIG3, runs.FIG4, fig5.SECTION, fig6.SECTION,
            runs.FIG7, paper.SECTION, readings.SECTION, lammps.SECTION, accuracy.SECTION)
