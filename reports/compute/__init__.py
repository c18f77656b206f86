"""Report computations: each module registers its functions (reports.registry.computation)."""
from diskfriction.reports.compute import accuracy, branches, runs  # noqa: F401  (registration)
