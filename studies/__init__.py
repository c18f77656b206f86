"""Studies that combine the disk problem's branches with the dynamics: one run per window
(verify.py), ensembles of runs and their fronts (ensemble.py), maps over scene parameters
(maps.py), on dask.distributed (cluster.py). The layer above diskfriction.models.chain and
diskfriction.dynamics; docs/architecture.md.
"""
