"""The shape the code keeps (issue: one engine, long functions and names): no function of the
package is longer than 80 lines of code, its docstring not counted."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "inerter"
LONGEST = 80


def _code_lines(node) -> int:
    body = node.body
    first = body[0]
    has_docstring = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
        and isinstance(first.value.value, str)
    start = (body[1].lineno if len(body) > 1 else node.end_lineno + 1) if has_docstring else first.lineno
    return node.end_lineno - start + 1


def test_no_function_is_longer_than_80_lines():
    long = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _code_lines(node) > LONGEST:
                long.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {node.name} ({_code_lines(node)})")
    assert not long, "functions longer than 80 lines of code:\n" + "\n".join(long)
