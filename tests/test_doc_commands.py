"""Every ``inerter`` command of the documentation's shell blocks (README.md and docs/*.md, not
docs/benchmarks/) is one the command line takes as written: its options parse (each command's
own parser, the delegated ones' too) and the scene files it names exist. Parsing only: which of
them run, and what they write, is tests/test_readme_commands.py's (README) and the reviewers'.
A renamed option, a dropped command or a moved scene fails here, naming the doc and the line."""
from __future__ import annotations

import argparse
import glob
import shlex

import pytest

from inerter.cli import main
from conftest import ROOT
from test_readme_commands import shell_lines

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def doc_commands() -> list[tuple[str, str]]:
    found = []
    for doc in DOCS:
        for line in shell_lines(doc.read_text()):
            if line.startswith("inerter "):
                found.append((doc.name, line))
    return found


COMMANDS = doc_commands()


class _Parsed(Exception):
    """Raised in place of running a command once its arguments parsed."""


def test_the_docs_have_commands():
    docs = {doc for doc, _ in COMMANDS}
    assert {"README.md", "usage.md", "fmu.md", "studies.md"} <= docs, docs


@pytest.mark.parametrize("doc, command", COMMANDS, ids=[f"{d}:{c}" for d, c in COMMANDS])
def test_a_documented_command_parses(doc, command, monkeypatch, capsys):
    original = argparse.ArgumentParser.parse_args

    def parse_only(self, args=None, namespace=None):
        original(self, args, namespace)
        raise _Parsed

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_only)
    words = shlex.split(command)[1:]
    argv = [w for word in words for w in (sorted(glob.glob(str(ROOT / word))) if "*" in word else [word])]
    with pytest.raises(_Parsed):
        main(argv)
    assert "error" not in capsys.readouterr().err
    for word in words:
        if word.startswith("scenarios/") and word.endswith(".toml") and "*" not in word:
            assert (ROOT / word).is_file(), f"{doc}: {command}: no {word}"
