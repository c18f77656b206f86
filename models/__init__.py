"""The geometries: the chain of disks on a substrate (chain/) and 2D frictional packings
(packing/), each a continuation problem on the core with its preparation and runs."""
