"""floatsim's browser viewer (viser). Importing this package imports no viser; `app.main` does.

Modules: `main` (start/serve, ViewerApp), `loop` (the simulation thread; no viser;
the settings it shows are a view of the running scene), `controls` (GUI inputs, generated from the
parameter declarations, that post commands), `scene` (3D nodes),
`readouts` (numbers and plots), `soak` (long-run benchmark).
"""
