"""Detection on a branch: samples with tracked spectra (samples.py), the collision detections
(detectors/, driven by collisions.py), certified intervals (certify.py, verdicts.py,
partial_splits.py), scans on worker processes (scans.py, spill.py), steps ending at a contact
change (root_ends.py), collisions located as defective double eigenvalues (locate.py) and folds,
branch and Hopf points (bifurcations.py)."""
