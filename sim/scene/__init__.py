"""The scene description: TOML presets, overrides and validation against the physics' own declarations, farms."""
