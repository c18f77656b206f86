"""Stepping along a branch: pseudo-arclength (arclength.py) with bordered Newton solves
(newton.py), the points between two accepted points (segment.py), derivatives by differences
(differences.py) and the arclength metric (weighting.py)."""
