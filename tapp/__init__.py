"""tapp: tracking accuracy prediction and orbit-determination analysis.

Trajectories with separately truncated variational equations, ground-station tracking
simulation (TAPP I), the matrix processor (TAPP III), Monte Carlo guidance (TAPP II) and the
batch/sequential estimators of the approximate-STM study.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("tapp")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"
