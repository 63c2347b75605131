"""Recording and replay: a take of the run, its offline HTML replay, its MP4 (drawn by headless chromium),
`floatsim run --record/--video`."""
