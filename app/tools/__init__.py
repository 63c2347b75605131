"""Programs that start a viewer and drive it, not unit tests: a page over viser's protocol, rendered pictures and
screenshots, hostile, soak, bandwidth and responsiveness campaigns."""
