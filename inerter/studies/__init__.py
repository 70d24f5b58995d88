"""Studies: work-precision benchmarks (:mod:`.bench`), parameter sweeps on dask (:mod:`.sweep`),
the built-in studies (:mod:`.builtin`) and plots (:mod:`.plotting`).

Layer: above :mod:`inerter.fmu`, below the command line (:mod:`inerter.cli`)."""
