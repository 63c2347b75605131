"""The ways a run can fail that a user must hear about, each in one line."""


class ConfigError(ValueError):
    """A user mistake in a scene, a flag or a control; its message is one line meant for the user."""


class SimulationDiverged(RuntimeError):
    """The state went non-finite or the energy blew up; the message names the time and a likely cause."""


class WriteFailed(ConfigError):
    """An output could not be written (a full disk, a mount gone): one line naming the file and why, exit 2 as for a
    user mistake (the command that catches it adds what it kept)."""

    def __init__(self, path, reason: str):
        super().__init__(f"cannot write {path}: {reason}")
        self.path, self.reason = str(path), reason


class Interrupted(Exception):
    """Raised by a loop that stopped because Ctrl-C asked it to."""
