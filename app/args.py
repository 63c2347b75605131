"""Command-line options of the viewer (no viser import here)."""

from dataclasses import dataclass


@dataclass
class ViewArgs:
    """Open the live 3D viewer in the browser."""

    scene: str = "damped"
    """Preset name (assets/scenes/NAME.toml) or path to a scene .toml."""
    host: str = "127.0.0.1"
    """Interface to bind (0.0.0.0 to share on the network)."""
    port: int = 8080
    """Port to serve on (a busy port moves to the next free one; the banner says which)."""
    token: str | None = None
    """A shared secret: only pages opened with ?token=TOKEN may drive the run (others watch); for --host beyond this machine."""
    share: bool = False
    """Let the page's share button open a public link through viser's share service (share.viser.studio): anyone
    with it can watch, and drive unless --token is given. Without it, pages cannot open one."""
    mesh: str | None = None
    """Your own closed mesh (STL, OBJ, PLY) as the body, with the scene's other settings."""
    mesh_unit: str = "m"
    """Unit of the mesh file's coordinates: m, cm, mm, in or ft."""
