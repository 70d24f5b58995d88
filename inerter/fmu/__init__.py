"""FMI 2.0 co-simulation FMUs: building them from scene files (:mod:`.build`), the native doStep
protocol of their binary (:mod:`.native`), running them through fmpy (:mod:`.run`) and coupled
systems (:mod:`.cosim`). The slave class itself is ``fmu_src/inerter_slave.py``.

Layer: above :mod:`inerter.api`."""
