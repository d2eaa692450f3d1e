"""Force models, variational equations and compiled propagation."""

from tapp.dynamics.propagate import PropagationError, Propagator, Trajectory
from tapp.dynamics.spec import (
    BODIES,
    ForceModel,
    GravitySpec,
    SurfaceForces,
    earth_model,
    parse_gravity,
)

__all__ = ["BODIES", "ForceModel", "GravitySpec", "PropagationError", "Propagator",
           "SurfaceForces", "Trajectory", "earth_model", "parse_gravity"]
