"""Every scene in the documentation runs: each ```toml block of README.md and docs/**/*.md,
through ``inerter run`` (in this process) and through its FMU (built and run by fmpy in one fresh
process for all of them: a built FMU is tested where no copy of the package shadows it), whose
outputs equal the solver's as the shipped scenes' do (tests/test_shipped_scenes.py's bound).

A block is a whole scene, or a *fragment of* a shipped scene, named in the line before it
("Fragment of `scenarios/X.toml`"): merged into that scene (docs/scene_format.md, General rules),
its tables are added to the scene's, an entry of [bodies], [joints], [elements] or [forces]
replaces the scene's of that name and its [[metrics]] are added. Each resulting scene is named
after its place (``doc_<file>_<line>``: one FMU module each) and run for SHORT seconds. A block
that fails names its file and line.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT, SCENARIOS
from inerter.cli import main as cli_main
from test_properties import dumps

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FRAGMENT = re.compile(r"[Ff]ragment of\s+`(scenarios/[\w/.-]+\.toml)`")
#: Entries of these tables are replaced whole by a fragment's of the same name.
REPLACED = ("bodies", "joints", "elements", "forces")
SHORT = 0.2
#: |FMU − solver| ≤ TOLERANCE_FACTOR · (rtol · max|solver| + atol), as for the shipped scenes.
TOLERANCE_FACTOR = 1000.0


@dataclass(frozen=True)
class Block:
    doc: Path
    line: int                   # of the opening fence
    text: str
    base: str | None            # the shipped scene a fragment is merged into

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(ROOT)}:{self.line}"

    @property
    def name(self) -> str:
        return f"doc_{self.doc.stem}_{self.line}"


def blocks() -> list[Block]:
    found = []
    for doc in DOCS:
        lines = doc.read_text().splitlines()
        for i, line in enumerate(lines):
            if line.strip() != "```toml":
                continue
            end = next(j for j in range(i + 1, len(lines)) if lines[j].strip() == "```")
            match = FRAGMENT.search(_paragraph_before(lines, i))
            found.append(Block(doc, i + 1, "\n".join(lines[i + 1:end]), match.group(1) if match else None))
    return found


def _paragraph_before(lines, i) -> str:
    """The paragraph that ends right before line i (blank lines between skipped)."""
    j = i - 1
    while j >= 0 and not lines[j].strip():
        j -= 1
    start = j
    while start > 0 and lines[start - 1].strip() and not lines[start - 1].startswith("```"):
        start -= 1
    return " ".join(lines[start:j + 1])


def merge(base: dict, fragment: dict) -> dict:
    out = dict(base)
    for key, value in fragment.items():
        if key == "metrics":
            out[key] = list(base.get(key, [])) + list(value)
        elif key in REPLACED:
            out[key] = {**base.get(key, {}), **value}
        elif isinstance(value, dict) and isinstance(base.get(key), dict):
            out[key] = merge(base[key], value)
        else:
            out[key] = value
    return out


def scene_of(block: Block, folder: Path) -> Path:
    """The block's scene, written into `folder` (with the records a base scene reads, relative to it)."""
    try:
        data = tomllib.loads(block.text)
    except tomllib.TOMLDecodeError as exc:
        pytest.fail(f"{block.where}: the TOML block does not parse: {exc}")
    if block.base is not None:
        data = merge(tomllib.loads((ROOT / block.base).read_text()), data)
        records = ROOT / block.base
        if (records.parent / "records").is_dir() and not (folder / "records").exists():
            shutil.copytree(records.parent / "records", folder / "records")
    data.setdefault("scene", {})["name"] = block.name
    path = folder / f"{block.name}.toml"
    path.write_text(dumps(data))
    return path


BLOCKS = blocks()


def test_the_documentation_holds_scenes():
    assert len(BLOCKS) >= 3
    assert any(b.base for b in BLOCKS) and any(b.base is None for b in BLOCKS)
    for b in BLOCKS:
        assert b.base is None or (ROOT / b.base).is_file(), f"{b.where}: no shipped scene {b.base}"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each block's scene and its ``inerter run`` (in this process) exit status and output folder."""
    folder = tmp_path_factory.mktemp("doc_scenes")
    out = {}
    for block in BLOCKS:
        scene = scene_of(block, folder)
        target = folder / "solver" / block.name
        code = cli_main(["run", str(scene), "--stop-time", str(SHORT), "--out", str(target)])
        out[block] = (scene, code, target)
    return folder, out


@pytest.mark.parametrize("block", BLOCKS, ids=[b.where for b in BLOCKS])
def test_doc_scene_runs(runs, block):
    scene, code, target = runs[1][block]
    assert code == 0, f"{block.where}: inerter run exited {code}"
    csv = target / f"{block.name}.csv"
    assert csv.is_file(), f"{block.where}: no CSV"
    summary = json.loads((target / "summary.json").read_text())
    assert summary["status"] == "ok", f"{block.where}: {summary['message']}"


FMU_SCRIPT = r"""
import json, sys
from inerter.cli import main
jobs = json.loads(sys.argv[1])
codes = {}
for name, scene, out in jobs:
    codes[name] = main(["run", scene, "--model", "fmu", "--stop-time", sys.argv[2], "--out", out])
print(json.dumps(codes))
"""


@pytest.fixture(scope="module")
def fmu_runs(runs):
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    folder, solver = runs
    jobs = [(b.name, str(scene), str(folder / "fmu" / b.name)) for b, (scene, code, _) in solver.items() if code == 0]
    proc = subprocess.run([sys.executable, "-c", FMU_SCRIPT, json.dumps(jobs), str(SHORT)], cwd=folder,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return folder, json.loads(proc.stdout.strip().splitlines()[-1])


def _columns(csv: Path) -> dict[str, np.ndarray]:
    lines = csv.read_text().splitlines()
    names = [h.rsplit(" (", 1)[0] for h in lines[0].split(",")]
    data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return {n: data[:, i] for i, n in enumerate(names)}


@pytest.mark.parametrize("block", BLOCKS, ids=[b.where for b in BLOCKS])
def test_doc_scene_fmu_equals_the_solver(runs, fmu_runs, block):
    folder, codes = fmu_runs
    assert codes.get(block.name) == 0, f"{block.where}: the FMU run exited {codes.get(block.name)}"
    solver = _columns(runs[1][block][2] / f"{block.name}.csv")
    fmu = _columns(folder / "fmu" / block.name / f"{block.name}.csv")
    assert set(fmu) == set(solver), f"{block.where}: the FMU's outputs differ from the solver's"
    summary = json.loads((runs[1][block][2] / "summary.json").read_text())["settings"]
    assert np.allclose(fmu["time"], solver["time"], rtol=0, atol=1e-9), block.where
    for name, values in solver.items():
        bound = TOLERANCE_FACTOR * (summary["rtol"] * np.max(np.abs(values)) + summary["atol"])
        # (the CSVs hold 12 significant digits: a bound below that rounding is raised to it)
        bound = max(bound, 2e-12 * np.max(np.abs(values)))
        assert np.max(np.abs(fmu[name] - values)) <= bound, f"{block.where}: {name}"


def test_a_broken_block_names_its_file_and_line(tmp_path):
    broken = Block(ROOT / "README.md", 73, "[scene\nname = 1", None)
    with pytest.raises(pytest.fail.Exception, match=r"README\.md:73: the TOML block does not parse"):
        scene_of(broken, tmp_path)


def test_a_fragment_replaces_the_entries_it_names_and_adds_the_rest():
    base = {"elements": {"inerter": {"type": "inerter", "b": 1.0}, "spring": {"k": 2.0}},
            "experiment": {"stop_time": 1.0, "rtol": 1e-8}, "metrics": [{"kind": "peak"}]}
    fragment = {"elements": {"inerter": {"type": "inerter", "device": {}}}, "experiment": {"rtol": 1e-9},
                "outputs": {"derived": {"d": "x"}}, "metrics": [{"kind": "natural_frequency"}]}
    merged = merge(base, fragment)
    assert merged["elements"] == {"inerter": {"type": "inerter", "device": {}}, "spring": {"k": 2.0}}
    assert merged["experiment"] == {"stop_time": 1.0, "rtol": 1e-9}
    assert merged["outputs"] == {"derived": {"d": "x"}}
    assert merged["metrics"] == [{"kind": "peak"}, {"kind": "natural_frequency"}]
