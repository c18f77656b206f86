"""Spectra along a branch: dense eigensystems, classification and tracking (tracking.py), the
eigenvalues nearest a shift (nearest.py), a window of real parts (window.py), dense spectra on a
GPU (gpu.py) and full spectra refined from a nearby sample's (refinement.py, over the refinement
of every eigenpair, eigenpairs.py, and its Rayleigh quotient iterations, rayleigh.py)."""
