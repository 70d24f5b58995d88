"""The package's layers (README, "Package layout"): each layer imports only the layers below it,
the oracle and the engine never import each other (the contract in pyproject.toml, checked by
import-linter), and no module imports another that imports it back, however indirectly."""
import subprocess
import sys
from pathlib import Path

import grimp

ROOT = Path(__file__).resolve().parents[1]


def test_each_layer_imports_only_the_layers_below_it():
    lint = Path(sys.executable).with_name("lint-imports")
    done = subprocess.run([str(lint), "--config", str(ROOT / "pyproject.toml")], cwd=ROOT,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 kept, 0 broken" in done.stdout


def _cycles(graph) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), i.e. import circles,
    counting imports inside functions too."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    counter = [0]

    def visit(m):
        index[m] = low[m] = counter[0]
        counter[0] += 1
        stack.append(m)
        on_stack.add(m)
        for n in graph.find_modules_directly_imported_by(m):
            if n not in index:
                visit(n)
                low[m] = min(low[m], low[n])
            elif n in on_stack:
                low[m] = min(low[m], index[n])
        if low[m] == index[m]:
            comp = []
            while True:
                n = stack.pop()
                on_stack.discard(n)
                comp.append(n)
                if n == m:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for m in sorted(graph.modules):
        if m not in index:
            visit(m)
    return out


def test_no_module_imports_itself_back():
    graph = grimp.build_graph("inerter")
    # The package's __init__ files re-export their public names; a module importing its own
    # package's __init__ is not a circle between modules of the design, so packages are left out.
    for pkg in [m for m in graph.modules if (ROOT / m.replace(".", "/") / "__init__.py").exists()]:
        graph.remove_module(pkg)
    assert _cycles(graph) == []
