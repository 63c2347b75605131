"""The scene description: TOML presets, overrides and validation, the stated limits, farms."""
