"""The package's layers point one way (curvature <- remesh <- io/plot <- filters <- cli), no
import cycle, and no private name crosses a package; the design the README's module map shows."""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "curvdetail"
#: what each layer may import from the package (itself included)
LAYERS = {"curvature": 0, "remesh": 1, "io": 2, "plot": 2, "data": 0, "filters": 3, "evaluate": 3,
          "cli": 4, "__main__": 5, "__init__": 5}


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        yield name, path, path.name == "__init__.py"


def _imports(name, path, is_package):
    """(imported module, imported names) of every import, module level or inside a function."""
    package = name if is_package else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] == "curvdetail":
                yield target, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "curvdetail":
                    yield a.name, []


def _layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


MODULES = {name for name, _, _ in _modules()}


def _edges():
    """(importer, imported module, names): ``from pkg import mod`` counts as importing pkg.mod."""
    for name, path, pkg in _modules():
        for target, names in _imports(name, path, pkg):
            subs = [x for x in names if f"{target}.{x}" in MODULES]
            for x in subs:
                yield name, f"{target}.{x}", []
            rest = [x for x in names if x not in subs]
            if rest or not names:
                yield name, target, rest


EDGES = list(_edges())


def test_imports_point_down_the_layers():
    # the package's __init__ re-exports the curvature and io layers, so a module above io may use it
    upward = [(n, t) for n, t, _ in EDGES
              if (2 if t == "curvdetail" else LAYERS[_layer(t)]) > LAYERS[_layer(n)]]
    assert upward == []


def test_no_private_name_crosses_a_package():
    crossing = [(n, t, x) for n, t, names in EDGES for x in names + [t.rpartition(".")[2]]
                if x.startswith("_") and not x.startswith("__") and _layer(n) != _layer(t)]
    assert crossing == []


def test_no_import_cycle():
    modules = MODULES
    graph = {m: set() for m in modules}
    for n, t, names in EDGES:
        # a package's __init__ importing its own modules, or a module its package, is no cycle
        if t in modules and t != n and not n.startswith(t + ".") and not t.startswith(n + "."):
            graph[n].add(t)
    seen, stack, cycles = set(), [], []

    def visit(m):
        if m in stack:
            cycles.append(stack[stack.index(m):] + [m])
            return
        if m in seen:
            return
        seen.add(m)
        stack.append(m)
        for d in graph[m]:
            visit(d)
        stack.pop()

    for m in sorted(modules):
        visit(m)
    assert cycles == []


def test_no_module_over_about_500_lines():
    sizes = {str(p.relative_to(ROOT)): len(p.read_text().splitlines()) for p in ROOT.rglob("*.py")}
    assert {p: n for p, n in sizes.items() if n > 550} == {}
