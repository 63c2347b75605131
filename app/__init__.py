"""floatsim's browser viewer (viser). Importing this package imports no viser; `app.viewer` does."""
