"""polrig: simulation and calibration of polarization-sensor calibration rigs.

A thin layer over the C++ library (docs/python.md): every function calls the same code as the
`polrig` command, so results are the CLI's, bit for bit. Arrays are NumPy float64; units are in
the names (theta_R_deg, V_mean, L_IS in mm) and in every docstring.
"""
from ._polrig import *  # noqa: F401,F403
from ._polrig import __version__, git_revision  # noqa: F401

__all__ = [name for name in dir() if not name.startswith("_") and name not in ("git_revision",)]
