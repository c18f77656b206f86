"""The packing problem: N bidisperse frictional disks in a periodic box sheared with
Lees-Edwards boundaries, no substrate. Preparation (FIRE to a target pressure or packing
fraction, then friction switched on), the contact network found with a cell list, forces and
the sparse Jacobian from the generated kernels (docs/packings.md). A sibling of models/chain/ on the
same layer: built on the generic core and the symbolic kernels.
"""
from diskfriction.models import Model

MODEL = Model("packing", "gamma", "diskfriction.models.packing.commands")
