"""Every reach of the studies into `sim` beyond its public surface, in one place.

The studies use `Simulation` (its `step`, `frame`, `state`, `dt`), `load_scene`, `with_overrides`,
`SimulationDiverged`, `State`, `Frame` and `INTEGRATORS` directly. Anything else they need from the
physics package (bodies, force models, wet samples, rotations, the command-line plumbing) goes
through the short functions below, so that a redesign of the core is followed by editing this file
only. Bodies and simulations pass through here as opaque objects; what the studies read from them
comes back as plain numbers and arrays (`BodyView`, `FluidView`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim import INTEGRATORS, Simulation, State, load_scene
from sim.bodies.body import Body, make_box
from sim.bodies.rotation import quat_multiply, quat_to_matrix, rotation_quat
from sim.commands import dispatch  # noqa: F401 -- re-exported: `python -m studies` uses the same dispatcher
from sim.commands.progress import progress_bar  # noqa: F401 -- re-exported for studies.common
from sim.hydro.forces import Model
from sim.scene.config import FluidConfig
from sim.system.frame import BodyFrame, observe
from sim.water.seas import StillWater

# ---- reading a body or a simulation -------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class BodyView:
    """What the studies read from a body: body frame, SI units."""

    mass: float
    volume: float
    inertia: np.ndarray
    """(3,) principal moments, kg m^2."""
    r: np.ndarray
    """(n, 3) sample positions."""
    n: np.ndarray
    """(n, 3) outward sample normals."""
    area: np.ndarray
    """(n,) sample areas."""
    mesh_vertices: np.ndarray
    mesh_faces: np.ndarray
    q_input: np.ndarray
    """(4,) rotation from the principal frame to the frame the shape was given in (w, x, y, z)."""

    @property
    def n_samples(self) -> int:
        return len(self.area)


@dataclass(frozen=True)
class FluidView:
    rho: float
    g: float
    damping: float


def body(of: Simulation | Body) -> BodyView:
    """The body of a simulation, or a body made by `cube_body`/`body_from_samples`, as plain arrays."""
    b = of.body if isinstance(of, Simulation) else of
    return BodyView(b.mass, b.volume, b.inertia, b.r_body, b.n_body, b.area, b.mesh_vertices, b.mesh_faces, b.q_input_body)


def fluid(sim: Simulation) -> FluidView:
    p = sim.params
    return FluidView(p.rho, p.g, p.damping)


def stepping_backend() -> str:
    """Which backend advances the fixed-step integrators ('numba' or 'numpy')."""
    return getattr(Simulation(load_scene("rest")), "backend", "numpy")


def stability_limits(method: str) -> tuple[float, float]:
    """The integrator's declared stability limits on dt omega_heave and dt lambda_max."""
    cls = INTEGRATORS[method]
    return cls.heave_limit, cls.damping_limit


# ---- loads at a pose ------------------------------------------------------------------------------------


def frame_at(sim: Simulation, state: State) -> BodyFrame:
    """The diagnostics (forces, torques, wet area ...) of `sim`'s body and force model at `state`; numpy path."""
    return observe(sim.model, state)


def damping_matrix(sim: Simulation, state: State) -> np.ndarray:
    """6x6 D with (F, T) = -D (u, omega), world frame, of `sim`'s force model (its damping d) at `state`."""
    model = sim.model
    return model.damping_matrix(model.wetted(state.x_world, state.R_world_body))


def still_water_frame(of: Body, rho: float, g: float, state: State) -> BodyFrame:
    """Diagnostics of a bare body (from `cube_body`/`body_from_samples`) at `state` in still water, sampled model, no damping."""
    return observe(Model(of, StillWater(rho, g), FluidConfig(rho=rho, g=g, damping=0.0)), state)


# ---- bodies made by a study -----------------------------------------------------------------------------


def cube_body(s: float, points_per_edge: int, mass: float, name: str = "box") -> Body:
    """sim's own cube: N x N cell-centred samples per face."""
    return make_box((s,) * 3, points_per_edge, mass, name)


def body_from_samples(r, n, area, mass: float, inertia: np.ndarray, like: Body, name: str) -> Body:
    """A sim body from bare samples and their inertia, shown with (and given the volume of) `like`'s mesh."""
    return Body(r_body=r, n_body=n, area=area, mass=mass, inertia=inertia, volume=like.volume,
                radius=float(np.sqrt(np.einsum("ki,ki->k", r, r).max())), mesh_vertices=like.mesh_vertices,
                mesh_faces=like.mesh_faces, q_input_body=np.array([1.0, 0.0, 0.0, 0.0]), name=name)  # fmt: skip


# ---- rotations (unit quaternions w, x, y, z) ------------------------------------------------------------


def rotation_matrix(q: np.ndarray) -> np.ndarray:
    return quat_to_matrix(q)


def quat_from_rotvec(rotvec) -> np.ndarray:
    """Rotation by |rotvec| about rotvec (exact for any size, including 0)."""
    return rotation_quat(np.asarray(rotvec, float))


def quat_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return quat_multiply(a, b)


def leak_margin(sim: Simulation) -> float | None:
    """sim.hydro.hydrostatics.leak_margin of `sim`'s body and fluid: below LEAK_BAND the points model warns."""
    from sim.hydro.hydrostatics import leak_margin as margin

    return margin(sim.model.body, sim.params)


def leak_band() -> float:
    from sim.hydro.hydrostatics import LEAK_BAND

    return LEAK_BAND
