"""Parameter sweeps: the grid of cases (`grid`), one chunk of cases run as an ensemble (`chunk`),
and the backends that spread chunks over one core, all cores or a Dask cluster (`backends`)."""
