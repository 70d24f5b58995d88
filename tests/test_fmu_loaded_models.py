"""The FMU slave's models shared by the instances of one process (``_loaded_models`` in
fmu_src/inerter_slave.py): a later instance takes the models of an earlier one only when the scene
and every file it reads are the same bytes, and then runs as a fresh load would.
"""
from __future__ import annotations

import hashlib
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import inerter

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "tid_storey_2d.toml"      # reads a ground record beside it


@pytest.fixture(scope="module")
def slave():
    """fmu_src/inerter_slave.py, imported for these tests only (an FMU run later in the same
    process must import the slave its FMU carries)."""
    sys.path.insert(0, str(ROOT / "fmu_src"))
    try:
        import inerter_slave
    finally:
        sys.path.remove(str(ROOT / "fmu_src"))
    yield inerter_slave
    inerter_slave._LOADED.clear()
    sys.modules.pop("inerter_slave", None)


def _copy(folder: Path) -> Path:
    """The scene and its record in `folder`, as an FMU's resources/ holds them."""
    (folder / "records").mkdir(parents=True)
    shutil.copy2(SCENE, folder / SCENE.name)
    shutil.copy2(SCENE.parent / "records" / "synthetic_x.csv", folder / "records" / "synthetic_x.csv")
    return folder / SCENE.name


def _models(slave, scene: Path) -> dict:
    data = scene.read_bytes()
    return slave._loaded_models(scene, data, hashlib.sha256(data).hexdigest())


def test_a_second_instance_of_the_same_files_takes_the_loaded_models(slave, tmp_path):
    slave._LOADED.clear()
    first = _models(slave, _copy(tmp_path / "a"))
    second = _models(slave, _copy(tmp_path / "b"))     # another extraction of the same FMU
    assert second is first
    # ... and steps as a model loaded afresh: the same samples bit for bit (the explicit reference
    # is a load of the repository's scene, sharing nothing with the slave's).
    fresh = inerter.load(SCENE)
    ours = second[()].simulate(stop_time=0.5, output_interval=0.01, metrics=False, path="numpy")
    ref = fresh.simulate(stop_time=0.5, output_interval=0.01, metrics=False, path="numpy")
    for name in ref.names:
        assert np.array_equal(ours[name], ref[name], equal_nan=True), name


def test_a_changed_record_is_loaded_again(slave, tmp_path):
    slave._LOADED.clear()
    first = _models(slave, _copy(tmp_path / "a"))
    scene = _copy(tmp_path / "b")
    record = scene.parent / "records" / "synthetic_x.csv"
    lines = record.read_text().splitlines()
    body = [i for i, line in enumerate(lines) if line.strip() and not line.startswith("#")]
    fields = lines[body[-1]].split(",")
    fields[1] = repr(float(fields[1]) + 1.0)              # the same scene file, another record
    lines[body[-1]] = ",".join(fields)
    record.write_text("\n".join(lines) + "\n")
    second = _models(slave, scene)
    assert second is not first
    g1 = first[()].scene.effects["ground_acceleration"]
    g2 = second[()].scene.effects["ground_acceleration"]
    assert not np.array_equal(g1.record[1], g2.record[1])


def test_a_missing_record_is_the_loads_error(slave, tmp_path):
    slave._LOADED.clear()
    _models(slave, _copy(tmp_path / "a"))
    scene = _copy(tmp_path / "b")
    (scene.parent / "records" / "synthetic_x.csv").unlink()
    with pytest.raises(inerter.SceneError, match="synthetic_x.csv"):
        _models(slave, scene)


def test_two_builds_of_one_scene_run_in_one_process(tmp_path):
    """An FMU of a copy of a scene under another file name (the same [scene] name, so the same
    model identifier) after the scene's own FMU, in one process, and the first again: each runs
    its own scene. Before, pythonfmu's binary was given the first build's module, whose class
    read its own scene file from the second FMU's resources/: fmi2Instantiate failed with a
    FileNotFoundError. Reference: each FMU's results against the solver's run of its own scene."""
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu

    scene = ROOT / "scenarios" / "hard" / "stiff_1dof_2d.toml"
    copy = tmp_path / "stiff_copy.toml"
    copy.write_text(scene.read_text().replace('d0 = { value = 1.0e-3,', 'd0 = { value = 2.0e-3,'))
    fmus = {path: build(path, tmp_path / path.stem) for path in (scene, copy)}
    assert fmus[scene].name == fmus[copy].name                 # one model identifier
    for path in (scene, copy, scene):
        fmu = simulate_fmu(path, stop_time=0.01, step=1e-3, fmu_path=fmus[path], metrics=False)
        solver = inerter.load(path).simulate(stop_time=0.01, output_interval=1e-3, metrics=False)
        assert fmu.status == "ok", fmu.message
        np.testing.assert_allclose(fmu["P.r[1]"], solver["P.r[1]"], rtol=0, atol=1e-12)
