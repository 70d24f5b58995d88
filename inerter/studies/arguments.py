"""The commands' argument parser, that of ``inerter`` and of the commands :mod:`inerter.cli` hands
over to the studies (``sweep``, ``sweep-plot``, ``study``, ``bench``, ``device-study``)."""
from __future__ import annotations

import argparse


class Parser(argparse.ArgumentParser):
    """argparse, with a usage error on one line (the command's -h gives the rest)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} -h)\n")
