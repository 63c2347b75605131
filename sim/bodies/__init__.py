"""Rigid bodies: their surface samples and meshes, state, rotations, joints to the world, the integrators."""
