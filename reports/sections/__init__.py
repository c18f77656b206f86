"""The report's sections in order; `--only KEY` picks some of them."""
import reports.compute  # noqa: F401  (registers the computations)
from reports.sections import fig2, fig6

SECTIONS = (fig2.SECTION, fig6.SECTION)
