"""The two ways a run can fail that a user must hear about, each in one line."""


class ConfigError(ValueError):
    """A user mistake in a scene, a flag or a control; its message is one line meant for the user."""


class SimulationDiverged(RuntimeError):
    """The state went non-finite or the energy blew up; the message names the time and a likely cause."""
