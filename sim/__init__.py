"""floatsim's physics: rigid bodies sampled on their surface, floating in water. No viewer, plotting or CLI imports."""

import os
import signal
import sys


def _interrupted_while_starting(signum, frame) -> None:
    os.write(2, b"floatsim: interrupted (Ctrl-C) while starting: nothing written\n")
    os._exit(130)


if sys.argv[:1] == ["-m"]:
    # `python -m sim` or `python -m app` (sys.argv[0] is '-m' while Python finds the module): Ctrl-C while the modules
    # load ends in one line and exit 130, not a traceback (or a KeyboardInterrupt some library's bare except swallows,
    # the run then going on); the command takes Ctrl-C over once it starts (commands.dispatch, app.main)
    signal.signal(signal.SIGINT, _interrupted_while_starting)

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
