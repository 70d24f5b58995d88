#!/usr/bin/env python3
"""Build one FMI 2.0 co-simulation FMU per scene into build/fmu/.

    python build_fmu.py                      # every scenarios/*.toml
    python build_fmu.py scenarios/two_bar_2d.toml -o build/fmu --force

An FMU is rebuilt only when its scene or the shipped code changed. Same as `inerter build-fmu`.
"""
import sys

from inerter.fmu.build import main

if __name__ == "__main__":
    sys.exit(main())
