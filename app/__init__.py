"""floatsim's browser viewer (viser). Importing this package imports no viser; `app.main` does.

Modules: `main` (start/serve, ViewerApp), `loop` (the simulation thread; no viser), `limits`
(valid ranges, clamping), `controls` (GUI inputs that post commands), `scene` (3D nodes),
`readouts` (numbers and plots), `soak` (long-run benchmark).
"""
