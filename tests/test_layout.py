"""The package's shape: folders by concern, arrows pointing down, no circles, small modules,
JAX's public API only."""
import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ikteach"
# what each folder may import from ikteach (besides itself); _runtime is the private room
ALLOWED = {
    "core": {"_runtime"},
    "characters": {"core", "_runtime"},
    "pictures": {"core", "characters"},
    "course": {"core", "characters", "pictures", "_runtime"},
    "_runtime": set(),
}
MAX_LINES = 400


def _module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path):
    """Every ikteach module a file imports (at any depth: lazy imports count too)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("ikteach")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if not module.startswith("ikteach"):
                continue
            for alias in node.names:
                full = f"{module}.{alias.name}"
                is_module = (PACKAGE.parent / full.replace(".", "/")).with_suffix(".py").exists() or \
                    (PACKAGE.parent / full.replace(".", "/") / "__init__.py").exists()
                out.add(full if is_module else module)
    return out


FILES = sorted(PACKAGE.rglob("*.py"))
GRAPH = {_module_name(f): _imports(f) for f in FILES}


def _folder(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in ALLOWED) else None


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_every_module_is_small_and_on_public_ground(path):
    text = path.read_text()
    assert len(text.splitlines()) <= MAX_LINES
    assert "jax._src" not in text and "xla_bridge" not in text
    assert "sys.modules[" not in text.replace("sys.modules[name]", "")  # no entries by hand


def test_arrows_point_down():
    wrong = []
    for module, imports in GRAPH.items():
        folder = _folder(module)
        if folder is None:  # ikteach/__init__.py: the facade
            continue
        for other in imports:
            target = _folder(other)
            if target is not None and target != folder and target not in ALLOWED[folder]:
                wrong.append(f"{module} -> {other}")
    assert wrong == []


def test_no_import_circles():
    def parents(m):
        parts = m.split(".")
        return [".".join(parts[:k]) for k in range(2, len(parts))]

    graph = {m: {i for i in imports if i in GRAPH and i != m and i not in parents(m)}
             for m, imports in GRAPH.items() if m != "ikteach"}
    seen, stack, cycles = set(), [], []

    def visit(m):
        if m in stack:
            cycles.append(stack[stack.index(m):] + [m])
            return
        if m in seen:
            return
        seen.add(m)
        stack.append(m)
        for n in sorted(graph.get(m, ())):
            visit(n)
        stack.pop()

    for m in sorted(graph):
        visit(m)
    assert cycles == []
