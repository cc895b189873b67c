"""The house at its boundaries: what seenerf may read of davis_io, and seenerf's wings in order."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SEENERF_ALLOWED = ("davis_io.session", "davis_io.geometry")
"""The only davis_io modules seenerf reads (and their submodules); the root only for its error."""
APP_LAYER = "seenerf.cli"
APP_LAYER_ALLOWED = ("davis_io.prepare",)
"""The verbs are the application above both packages: ``seecap fit`` prepares a session (its
calibration and poses, davis_io's stages) before it fits it."""
ROOT_NAMES_ALLOWED = {"SeecapError", "describe_error"}
VERB_TABLE = ROOT / "davis_io" / "cli" / "__init__.py"


def _modules(package: str) -> dict[str, Path]:
    modules = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        modules[name] = path
    return modules


def _imports(tree: ast.AST, module_level_only: bool = False):
    """``(node, imported module, names)`` of every import; function bodies skipped if asked."""
    stack = [tree]
    while stack:
        node = stack.pop()
        for child in ast.iter_child_nodes(node):
            if module_level_only and isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
            ):
                continue
            if isinstance(child, ast.Import):
                for alias in child.names:
                    yield child, alias.name, []
            elif isinstance(child, ast.ImportFrom) and child.level == 0 and child.module:
                yield child, child.module, [alias.name for alias in child.names]
            stack.append(child)


def _is_under(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


SEENERF = _modules("seenerf")
DAVIS_IO = _modules("davis_io")


@pytest.mark.parametrize("name", sorted(SEENERF))
def test_seenerf_reads_davis_io_only_through_session_and_geometry(name):
    tree = ast.parse(SEENERF[name].read_text())
    for node, module, names in _imports(tree):
        if not _is_under(module, "davis_io"):
            continue
        where = f"{name} line {node.lineno}: {module}"
        if module == "davis_io":
            assert names and set(names) <= ROOT_NAMES_ALLOWED, where
        else:
            allowed = SEENERF_ALLOWED + (APP_LAYER_ALLOWED if _is_under(name, APP_LAYER) else ())
            assert any(_is_under(module, a) for a in allowed), where


@pytest.mark.parametrize("name", sorted(DAVIS_IO))
def test_davis_io_never_imports_seenerf(name):
    path = DAVIS_IO[name]
    tree = ast.parse(path.read_text())
    for node, module, _ in _imports(tree):
        assert not _is_under(module, "seenerf"), f"{name} line {node.lineno}: {module}"
    named = [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and _is_under(node.value, "seenerf")
    ]
    if path != VERB_TABLE:
        assert not named, f"{name} names seenerf modules: {[n.value for n in named]}"


def test_only_the_verb_table_names_seenerf_modules():
    tree = ast.parse(VERB_TABLE.read_text())
    table = next(
        node.value
        for node in tree.body
        if isinstance(node, ast.AnnAssign) and getattr(node.target, "id", "") == "VERBS"
    )
    verb_modules = {value.value for value in table.values}
    named = {
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and _is_under(node.value, "seenerf")
    }
    assert named <= verb_modules
    assert all(module.startswith("seenerf.cli.") for module in named)


def _graph(wing_of) -> dict[str, set[str]]:
    """Module-level import edges between seenerf modules, each mapped by ``wing_of``."""
    graph: dict[str, set[str]] = {wing_of(name): set() for name in SEENERF}
    for name, path in SEENERF.items():
        for _, module, names in _imports(ast.parse(path.read_text()), module_level_only=True):
            targets = [module] + [f"{module}.{n}" for n in names if f"{module}.{n}" in SEENERF]
            for target in targets:
                if target in SEENERF and target != "seenerf":
                    graph[wing_of(name)].add(wing_of(target))
    for node, edges in graph.items():
        edges.discard(node)
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """One cycle of the graph as a path, or an empty list."""
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        path.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == 1:
                return path[path.index(target) :] + [target]
            if target not in state:
                found = visit(target)
                if found:
                    return found
        state[node] = 2
        path.pop()
        return []

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return []


def _wing(module: str) -> str:
    """``seenerf.<wing>`` of a module: its sub-package, or a top-level module itself."""
    return ".".join(module.split(".")[:2])


def test_seenerf_modules_import_without_cycles():
    assert _cycle(_graph(lambda name: name)) == []


def test_seenerf_wings_import_without_cycles():
    graph = _graph(_wing)
    assert {"seenerf.render", "seenerf.model", "seenerf.data", "seenerf.train"} <= set(graph)
    assert _cycle(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) == []


def test_function_local_imports_of_seenerf_say_why():
    """Outside the verbs (which defer torch until they run), a local import carries a comment."""
    for name, path in SEENERF.items():
        if _is_under(name, "seenerf.cli"):
            continue
        lines = path.read_text().splitlines()
        module_level = {
            node.lineno
            for node, _, _ in _imports(ast.parse("\n".join(lines)), module_level_only=True)
        }
        for node, module, _ in _imports(ast.parse("\n".join(lines))):
            if _is_under(module, "seenerf") and node.lineno not in module_level:
                said = "#" in lines[node.lineno - 1] or lines[node.lineno - 2].strip().startswith(
                    "#"
                )
                assert said, f"{name} line {node.lineno}: local import without a reason"


def _variant_name_comparisons(tree: ast.AST, names: set[str]) -> list[int]:
    """Lines comparing anything with a string that is a variant's name (==, !=, in)."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            if any(isinstance(o, ast.Constant) and o.value in names for o in operands):
                lines.append(node.lineno)
    return lines


def test_no_code_branches_on_a_variant_name_outside_the_registry():
    from seenerf.model.variants import VARIANTS

    registry = ROOT / "seenerf" / "model" / "variants.py"
    sources = [p for d in ("seenerf", "davis_io", "tools") for p in (ROOT / d).rglob("*.py")]
    found = {
        str(path.relative_to(ROOT)): lines
        for path in sources
        if path != registry
        and (lines := _variant_name_comparisons(ast.parse(path.read_text()), set(VARIANTS)))
    }
    assert found == {}, "variants carry objects for what they do; compare those, not names"
    planted = ast.parse('if config.model.variant == "oracle":\n    pass\n')
    assert _variant_name_comparisons(planted, set(VARIANTS)) == [1]
