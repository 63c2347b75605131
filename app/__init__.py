"""floatsim's browser viewer (viser). Importing this package imports no viser; `app.main` does.

Packages: `live` (the simulation thread, which needs no viser, and the page's controls and readouts), `drawn` (the 3D
nodes), `recording` (takes, replays, video), `guards` (what a page may do), `tools` (the hostile campaign, bandwidth).
"""

import sim  # noqa: F401  (first: `python -m app` then answers a Ctrl-C while its modules load with one line, exit 130)
