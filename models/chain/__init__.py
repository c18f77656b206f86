"""The disk problem: the chain of frictional disks on a substrate as a continuation problem
(equilibria.py: DiskEquilibria, with the tangential history in its commit hook), its sweeps in
F_x from rest (sweep.py), the equilibrium at a load (equilibrium.py), the windows between
collisions (windows.py), the records of a branch (records.py), and what a sweep costs in memory
and time (memory.py, cost.py). Built on the generic core (diskfriction.continuation) and the
scene's kernels (diskfriction.symbolic); docs/architecture.md.
"""
from diskfriction.models import Model

MODEL = Model("chain", "F_x", "diskfriction.models.chain.commands")
