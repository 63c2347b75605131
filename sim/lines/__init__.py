"""Mooring lines: MoorDyn's coupling and input files, the elastic catenary, the lines' energy, lines driven alone."""
