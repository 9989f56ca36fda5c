"""Driving the printed hand's servos over their serial bus (``phantom-cad drive``; docs/driving.md):
the Feetech protocol (``protocol``), the port (``bus``), the driver with its safety, zero and
sweeps (``driver``), and a simulated bus to run them without a hand (``simbus``).

A layer above the kinematics and the postures (a pose is the posture library's commands) and
below the command line; imports no CAD library.
"""
