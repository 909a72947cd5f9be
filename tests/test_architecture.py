"""The structure docs/architecture.md promises, read from the source (nothing imported): no
import cycles, each layer imports only its own layer and the layers below it, and the image,
colour and command-line libraries each imported by their one home.

Imports at module level and inside functions count alike. Each test has a planted case that
must fail (a module graph built by hand), so that a check that can no longer see anything is
caught too.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "envconv"

#: Layers from the top (index 0) down; a module belongs to the first entry whose prefix names it.
LAYERS = [
    ("cli", ["envconv.cli", "envconv.__main__"]),
    ("engine", ["envconv.engine"]),
    ("views", ["envconv.views"]),
    ("resample", ["envconv.resample"]),
    ("io", ["envconv.io"]),
    ("color", ["envconv.color"]),
    ("envmap", ["envconv.envmap"]),
    ("layouts", ["envconv.layouts"]),
    ("foundation", ["envconv.errors", "envconv.lazy", "envconv.limits"]),
]
#: Modules that live in one layer's package and serve every layer as another: the native core's
#: only door (the layouts' point maps call it), and the memory guard, which refuses a read, an
#: encode or an allocation before it happens.
SERVICES = {"envconv.resample.kernels": "foundation", "envconv.engine.memory": "foundation"}
#: The upward imports allowed, each by name and why. The memory guard estimates a conversion
#: from the layout and its MIP sizes; the writer, and its plan of what it will write, ask the
#: chain's level count of its one home.
ALLOWED_UP = {
    ("envconv.engine.memory", "envconv.layouts"),
    ("envconv.engine.memory", "envconv.resample.mips"),
    ("envconv.io.writer", "envconv.resample.mips"),
    ("envconv.io.write_plan", "envconv.resample.mips"),
}
#: Third-party libraries and the only modules (prefixes) that may import them.
LIBRARY_HOMES = {
    "click": ("envconv.cli",),
    "OpenImageIO": ("envconv.io",),
    "OpenEXR": ("envconv.io",),
    "Imath": ("envconv.io",),
    "PyOpenColorIO": ("envconv.color.ocio",),
}


def _modules(root: Path = PACKAGE) -> dict[str, Path]:
    modules = {}
    for path in root.rglob("*.py"):
        name = ".".join(path.relative_to(root.parent).with_suffix("").parts)
        modules[name.removesuffix(".__init__")] = path
    return modules


def _imports(name: str, path: Path) -> set[str]:
    """Absolute names of everything ``name`` imports: ``from X import y`` gives X.y, which
    :func:`_graph` resolves to module X.y, or to X when y is a name in it."""
    found = set()
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text("utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                prefix = ".".join(base + ([node.module] if node.module else []))
            else:
                prefix = node.module or ""
            found.update(f"{prefix}.{alias.name}" for alias in node.names)
    return found


def _graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module → the package's modules it imports (a name resolves to its longest known module)."""
    graph = {}
    for name, path in modules.items():
        deps = set()
        for target in _imports(name, path):
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target not in (name, "envconv"):
                deps.add(target)
        graph[name] = deps
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, on_stack, stack, found, counter = {}, {}, set(), [], [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def _layer(module: str) -> int | None:
    if module in SERVICES:
        module = SERVICES[module]
        return next(i for i, (name, _) in enumerate(LAYERS) if name == module)
    for i, (_, prefixes) in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return i
    return None


def _upward(graph: dict[str, set[str]]) -> list[str]:
    bad = []
    for module, deps in graph.items():
        here = _layer(module)
        for dep in deps:
            there = _layer(dep)
            if here is None or there is None or (module, dep) in ALLOWED_UP:
                continue
            if any(dep == a or dep.startswith(a + ".") for m, a in ALLOWED_UP if m == module):
                continue
            if there < here:
                bad.append(f"{module} ({LAYERS[here][0]}) imports {dep} ({LAYERS[there][0]})")
    return sorted(bad)


def test_every_module_has_a_layer():
    assert [m for m in _modules() if m != "envconv" and _layer(m) is None] == []


def test_no_import_cycles():
    assert _cycles(_graph(_modules())) == []


def test_the_cycle_check_sees_a_planted_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]]


def test_layers_import_only_downwards():
    assert _upward(_graph(_modules())) == []


def test_the_layer_check_sees_a_planted_upward_import():
    graph = {"envconv.io.reader": {"envconv.engine.walk"}, "envconv.engine.walk": set()}
    assert _upward(graph) == ["envconv.io.reader (io) imports envconv.engine.walk (engine)"]


@pytest.mark.parametrize("library", sorted(LIBRARY_HOMES))
def test_libraries_are_imported_only_by_their_home(library):
    homes = LIBRARY_HOMES[library]
    offenders = []
    for name, path in _modules().items():
        imported = {target.split(".")[0] for target in _imports(name, path)}
        if library in imported and not any(name == h or name.startswith(h + ".") for h in homes):
            offenders.append(name)
    assert offenders == []


def test_old_module_names_still_import_the_moved_modules():
    """The paths the docs gave before the regroup (docs/python.md, docs/architecture.md)."""
    import importlib

    import envconv

    for old, new in envconv.MOVED.items():
        assert importlib.import_module(f"envconv.{old}") is importlib.import_module(
            f"envconv.{new}"
        ), old
        assert importlib.import_module(f"envconv.{new}").__spec__.name == f"envconv.{new}"
    from envconv.color import to_working
    from envconv.resample import default_size

    assert default_size.__module__ == "envconv.resample.options"
    assert to_working.__module__ == "envconv.color.ocio"
