"""The collision detections, by name (as scipy.integrate's METHODS): DETECTORS[mode] is the
Detector (base.py) that StepScan (collisions.py) drives for DetectionParams.mode.

Adding a detector: a subclass of Detector in a module of this folder (its verdict on an
interval, what it does with an interval holding events, when an event is final, and what its
samples carry), and one entry here; `bifurcate --detection NAME` then takes it
(docs/continuation.md, Adding a detector)."""
from diskfriction.continuation.detection.detectors.base import Collision, Detector, Kind, sample_discriminant
from diskfriction.continuation.detection.detectors.exhaustive import Exhaustive
from diskfriction.continuation.detection.detectors.fast import Fast

DETECTORS: dict[str, Detector] = {d.name: d for d in (Fast(), Exhaustive())}

__all__ = ["Collision", "DETECTORS", "Detector", "Kind", "sample_discriminant"]
