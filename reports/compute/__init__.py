"""Report computations: the functions each module marks (reports.registry.computation)."""
from diskfriction.reports.compute import accuracy, branches, runs
from diskfriction.reports.registry import collect

COMPUTATIONS = collect(accuracy, branches, runs)
"""{name: Computation} of every computation a section can need."""
