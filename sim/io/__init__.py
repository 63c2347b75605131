"""Coefficient files in: WAMIT's output and floatsim's own solves."""
