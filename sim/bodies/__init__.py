"""Rigid bodies: their surface samples and meshes, mass and inertia, state, rotations, the wet part of their surface."""
