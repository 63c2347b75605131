"""How one body moves: the time integrators with their declared orders, and a joint to the world with its take-off."""
