"""The package's layout: imports point one way, from the interfaces down to the algebra.

Every import inside jetnh/ counts, at module level and inside functions (a late import is
a dependency all the same): none may form a cycle, and none may point from a lower layer
to a higher one, except the few declared below with their reason.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "jetnh"

#: the layers, lowest first; a module belongs to the layer of its longest listed prefix
#: ("numeric" holds jetnh.numeric and every jetnh.numeric.*)
LAYERS = (
    ("base", ("errors", "frozen")),
    ("algebra", ("algebra",)),
    ("geometry", ("geometry",)),
    ("mechanics", ("mechanics",)),
    ("kernel format", ("numeric.layout",)),
    ("code generation", ("numeric.codegen",)),
    ("numeric", ("numeric",)),
    ("interfaces", ("display", "modelfile", "models", "strategies", "sweep")),
    ("package", ("",)),
    ("command line", ("cli", "__main__")),
)

#: what the compiled-kernel package (store, loader, record, calls) may import inside
#: jetnh.numeric: the format, the code generator, and the compiled loops' types
KERNELS_IMPORT = ("numeric.layout", "numeric.codegen", "numeric.methods", "numeric.kernels")

#: upward imports allowed, (importer or "*", imported, function-level only) -> reason
ALLOWED_UPWARD = {
    ("*", "display", True): "objects render themselves through jetnh.display in their "
                            "_repr_html_/_repr_latex_/__str__, imported when first shown",
}

#: cycles allowed for now, each to be removed when the named work lands
ALLOWED_CYCLES: dict = {}


def _modules() -> dict[str, Path]:
    """Module name relative to jetnh ("" for the package) -> file."""
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _resolve(name: str) -> str | None:
    """An absolute dotted name inside jetnh -> its module key, else None."""
    if name == "jetnh":
        return ""
    if name.startswith("jetnh."):
        key = name[len("jetnh."):]
        return key if key in MODULES else None
    return None


def imports() -> list[tuple[str, str, int, bool]]:
    """(importer, imported, line, inside a function) for every import between modules."""
    out = []
    for mod, path in MODULES.items():
        package = ["jetnh", *mod.split(".")] if mod else ["jetnh"]
        if path.name != "__init__.py":
            package = package[:-1]
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = set(map(id, tree.body))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [_resolve(a.name) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = (".".join(package[:len(package) - node.level + 1]
                                 + ([node.module] if node.module else []))
                        if node.level else (node.module or ""))
                subs = [_resolve(f"{base}.{a.name}") for a in node.names]
                targets = [s for s in subs if s is not None] or [_resolve(base)]
            else:
                continue
            for t in targets:
                if t is not None and t != mod:
                    out.append((mod, t, node.lineno, id(node) not in top))
    return out


def layer(mod: str) -> int:
    best = max(((len(p), i) for i, (_, prefixes) in enumerate(LAYERS) for p in prefixes
                if mod == p or (p and mod.startswith(p + "."))), default=None)
    assert best is not None, f"jetnh.{mod} is in no layer: declare it in LAYERS"
    return best[1]


def where(mod: str, line: int) -> str:
    return f"{MODULES[mod].relative_to(ROOT.parent)}:{line}"


def _cycles(edges: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(comp)

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def test_every_module_has_a_layer():
    for mod in MODULES:
        layer(mod)


def test_the_import_scanner_sees_late_imports():
    found = {(a, b, late) for a, b, _, late in imports()}
    assert ("", "numeric", True) in found                   # jetnh.__getattr__
    assert ("mechanics.system", "mechanics.equations", True) in found  # System.equations
    assert ("mechanics.integrals", "mechanics.system", False) in found


def test_no_import_cycles():
    edges: dict[str, set[str]] = {}
    for a, b, _, _ in imports():
        edges.setdefault(a, set()).add(b)
    cycles = [c for c in _cycles(edges) if frozenset(c) not in ALLOWED_CYCLES]
    report = [" <-> ".join(sorted(f"jetnh.{m}" for m in c)) + ": "
              + ", ".join(f"{where(a, line)} imports jetnh.{b}" for a, b, line, _ in imports()
                          if a in c and b in c) for c in cycles]
    assert not report, "import cycles:\n" + "\n".join(report)


def test_allowed_cycles_still_exist():
    """An allowed cycle that is gone must leave ALLOWED_CYCLES (so the list stays true)."""
    edges: dict[str, set[str]] = {}
    for a, b, _, _ in imports():
        edges.setdefault(a, set()).add(b)
    present = {frozenset(c) for c in _cycles(edges)}
    gone = [sorted(c) for c in ALLOWED_CYCLES if c not in present]
    assert not gone, f"remove these from ALLOWED_CYCLES, they are broken now: {gone}"


def against_layers(edges) -> list[str]:
    """The imports of ``edges`` (as from ``imports()``) that point up the layers and are
    not allowed, each as 'file:line: importer (layer) imports imported (layer)'."""
    bad = []
    for a, b, line, late in edges:
        if layer(b) <= layer(a):
            continue
        if (("*", b, True) in ALLOWED_UPWARD and late) or (a, b, late) in ALLOWED_UPWARD:
            continue
        bad.append(f"{where(a, line)}: jetnh.{a or '(package)'} ({LAYERS[layer(a)][0]}) "
                   f"imports jetnh.{b} ({LAYERS[layer(b)][0]})"
                   + (" inside a function" if late else ""))
    return bad


def test_imports_point_down_the_layers():
    bad = against_layers(imports())
    assert not bad, "imports against the layer order:\n" + "\n".join(bad)


def test_a_violation_names_its_file_and_line():
    assert against_layers([("mechanics.system", "numeric.scene", 12, True),
                           ("mechanics.system", "display", 40, True),
                           ("mechanics.system", "display", 41, False),
                           ("mechanics.equations", "mechanics.system", 7, False)]) == [
        "jetnh/mechanics/system.py:12: jetnh.mechanics.system (mechanics) imports jetnh.numeric.scene "
        "(numeric) inside a function",
        "jetnh/mechanics/system.py:41: jetnh.mechanics.system (mechanics) imports jetnh.display "
        "(interfaces)"]


def test_the_kernel_package_imports_only_what_it_stores_and_calls():
    """jetnh.numeric.kernels sits between code generation and the numeric values: it
    never imports a scene, a trajectory or a driver."""
    bad = [f"{where(a, line)}: jetnh.{a} imports jetnh.{b}" for a, b, line, _ in imports()
           if a.startswith("numeric.kernels") and b.startswith("numeric")
           and not any(b == p or b.startswith(p + ".") for p in KERNELS_IMPORT)]
    assert not bad, "\n".join(bad)
