"""The drawn scene: water, the body's mesh and samples, its waterline, buoyancy markers, the lines coloured by tension, the camera."""
