"""floatsim's physics: rigid bodies sampled on their surface, floating in water. No viewer, plotting or CLI imports."""

import os

# Our matrices are 3x3 and 6x6: BLAS threads only add overhead and fight the viewer for cores.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from sim.bodies.body import Body, make_body  # noqa: E402
from sim.bodies.state import State
from sim.dynamics.integrators import INTEGRATORS, make_integrator
from sim.errors import ConfigError, SimulationDiverged
from sim.hydro.forces import TERMS, Model
from sim.parameters import Param
from sim.scene.config import (
    PARAMS,
    BodyConfig,
    FluidConfig,
    InitialConfig,
    SceneConfig,
    StepConfig,
    WavesConfig,
    load_scene,
    with_overrides,
)
from sim.simulation import Simulation
from sim.system.frame import CSV_COLUMNS, BodyFrame, Frame, observe
from sim.water.seas import StillWater

__all__ = ["Body", "make_body", "ConfigError", "SceneConfig", "BodyConfig", "FluidConfig", "InitialConfig", "StepConfig", "WavesConfig", "PARAMS", "Param", "load_scene", "with_overrides", "Model",
           "TERMS", "StillWater", "INTEGRATORS", "make_integrator", "CSV_COLUMNS", "BodyFrame", "Frame", "Simulation", "SimulationDiverged", "observe", "State"]  # fmt: skip
