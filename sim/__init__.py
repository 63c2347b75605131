"""floatsim's physics: rigid bodies sampled on their surface, floating in water. No viewer imports."""

from .body import Body, make_body
from .config import ConfigError, SceneConfig, load_scene, with_overrides
from .forces import Model, Params
from .integrators import INTEGRATORS, make_integrator
from .simulation import CSV_COLUMNS, Frame, Simulation, SimulationDiverged, observe
from .state import State

__all__ = ["Body", "make_body", "ConfigError", "SceneConfig", "load_scene", "with_overrides", "Model", "Params",
           "INTEGRATORS", "make_integrator", "CSV_COLUMNS", "Frame", "Simulation", "SimulationDiverged", "observe", "State"]  # fmt: skip
