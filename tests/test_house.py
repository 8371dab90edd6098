"""The package's layout rules (CONTRIBUTING.md, "The house"), read from its source.

* No import inside a function, except of an optional extra or a platform-only
  module: an import hidden in a function is how an import circle hides.
* No module imports another module of the package in a circle.
* Only a folder's ``__init__.py`` re-exports names (``noqa: F401``).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "skfem_npfem"

#: What may be imported inside a function: the optional extras (viz, sweep)
#: and modules that exist on some platforms only.
DEFERRED_OK = {
    "PIL",
    "cloudpickle",
    "dask",
    "distributed",
    "fcntl",
    "imageio",
    "imageio_ffmpeg",
    "matplotlib",
    "pandas",
    "pyvista",
    "resource",
    "vtkmodules",
}


def modules() -> dict[str, ast.Module]:
    """Dotted name -> parsed source of every module of the package."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = ast.parse(path.read_text(), str(path))
    return out


def imported(name: str, node: ast.Import | ast.ImportFrom, package: bool) -> list[str]:
    """The dotted names an import statement of module ``name`` loads."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = name.split(".") if package else name.split(".")[:-1]
    if node.level:
        base = base[: len(base) - (node.level - 1)]
        stem = ".".join([*base, node.module] if node.module else base)
    else:
        stem = node.module or ""
    return [stem] + [f"{stem}.{a.name}" for a in node.names]


def test_no_import_inside_a_function_but_of_an_optional_extra():
    hidden = []
    for name, tree in modules().items():
        package = (PACKAGE.parent / name.replace(".", "/") / "__init__.py").exists()
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import | ast.ImportFrom):
                    first = imported(name, node, package)[0]
                    top = first.split(".")[0]
                    if top in DEFERRED_OK or first.startswith("skfem_npfem.viz"):
                        continue
                    hidden.append(f"{name}:{node.lineno} imports {first}")
    assert hidden == []


def test_no_import_circle_between_modules():
    mods = modules()
    edges: dict[str, set[str]] = {}
    for name, tree in mods.items():
        package = (PACKAGE.parent / name.replace(".", "/") / "__init__.py").exists()
        deps = set()
        for node in tree.body:  # module level: what loads with the module
            if isinstance(node, ast.Import | ast.ImportFrom):
                deps |= {d for d in imported(name, node, package) if d in mods}
        edges[name] = deps - {name}
    # A package's __init__ loads its modules: an edge into a package is an
    # edge into its __init__, which the walk below follows.
    state: dict[str, int] = {}
    circle: list[str] = []

    def visit(node: str, path: list[str]) -> bool:
        state[node] = 1
        for dep in sorted(edges[node]):
            if state.get(dep) == 1:
                circle.extend([*path[path.index(dep) :], dep])
                return True
            if dep not in state and visit(dep, [*path, dep]):
                return True
        state[node] = 2
        return False

    for start in sorted(edges):
        if start not in state and visit(start, [start]):
            break
    assert circle == []


def test_only_init_files_re_export():
    found = [
        f"{path.relative_to(PACKAGE.parent)}:{i}"
        for path in PACKAGE.rglob("*.py")
        if path.name != "__init__.py"
        for i, line in enumerate(path.read_text().splitlines(), 1)
        if "noqa: F401" in line
    ]
    assert found == []
