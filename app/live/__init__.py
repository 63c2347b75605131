"""The running viewer: the simulation thread, the GUI's controls and readouts, the upload of a body, share links, the About pane."""
