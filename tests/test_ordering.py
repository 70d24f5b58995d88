"""The engine's reverse Cuthill–McKee ordering of the augmented matrix (inerter.engine.compiled):
its band is as narrow as scipy.sparse.csgraph's reverse_cuthill_mckee gives (the reference), on
chains whose augmented matrix is block-banded and on the shipped 3D scenes."""
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee as scipy_rcm

import inerter
from inerter.engine import compiled

ROOT = Path(__file__).resolve().parents[1]


def _band(S, order):
    perm = np.empty(len(order), dtype=np.int64)
    perm[order] = np.arange(len(order))
    i, j = np.nonzero(S)
    d = perm[i] - perm[j]
    return int(max(d.max(), 0)), int(max(-d.min(), 0))


def _pattern(path):
    mech = inerter.load(str(path)).mechanism
    if mech.scene.dimension == 3:
        return compiled.sparsity(compiled.flatten3(mech))
    return compiled.sparsity(compiled.flatten(mech))


def _chain(tmp_path, links):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from chain_scene import write_chain
    finally:
        sys.path.pop(0)
    return write_chain(tmp_path / f"chain{links}.toml", links)


@pytest.mark.parametrize("scene", ["chain8", "chain64", "double_pendulum_3d", "braced_frame_3d", "two_bar_2d"])
def test_band_as_narrow_as_scipys(scene, tmp_path):
    path = _chain(tmp_path, int(scene[5:])) if scene.startswith("chain") else ROOT / "scenarios" / f"{scene}.toml"
    S = _pattern(path)
    symmetric = S | S.T
    ours = _band(S, compiled.reverse_cuthill_mckee(symmetric))
    reference = _band(S, scipy_rcm(csr_matrix(symmetric), symmetric_mode=True))
    assert sum(ours) <= sum(reference)
    order = compiled.reverse_cuthill_mckee(symmetric)
    assert sorted(order.tolist()) == list(range(S.shape[0]))      # a permutation


def test_disconnected_parts_are_all_ordered():
    S = np.zeros((5, 5), dtype=bool)
    S[0, 1] = S[1, 0] = S[3, 4] = S[4, 3] = True          # two parts and a lone unknown (2)
    order = compiled.reverse_cuthill_mckee(S)
    assert sorted(order.tolist()) == [0, 1, 2, 3, 4]
