"""Other codes as peers: a scene exported to LAMMPS, run there, and compared with ours.

Data flow: scenes -> symbolic -> continuation / dynamics -> peers (lammps_deck writes LAMMPS
input, lammps_run runs it and reads it back, crosscheck runs both codes from one state).
docs/lammps.md says how the scene maps onto LAMMPS and what was verified.
"""
