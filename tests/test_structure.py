"""The package's imports flow one way: a test parses every module's imports (also those
inside functions) and fails on a cycle. The range found from the pair runs the method on
a reduced pair (``search_range`` -> ``pipeline``); the public ``match``/``run``, which
find the range when none is given, sit above both (``api``)."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "vsmatch"

KNOWN_CYCLES: list[set[str]] = []


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph() -> dict[str, set[str]]:
    modules = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph = {name: set() for name in modules}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(parts + ([node.module] if node.module else []))
                targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            for target in targets:
                # A package loading its own submodules is its interface, not a cycle.
                if target in modules and target != name and not target.startswith(name + "."):
                    graph[name].add(target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in graph[node]:
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(component)

    for node in graph:
        if node not in index:
            visit(node)
    return found


def test_the_imports_have_no_cycle_but_the_known_one():
    found = cycles(import_graph())
    assert [c for c in found if c not in KNOWN_CYCLES] == [], found


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [{"a", "b", "c"}]


def test_no_window_function_is_used_so_any_opencv_wheel_serves():
    """vsmatch depends on opencv-python-headless, and runs as well on the wheel with windows
    a user may have (docs/python.md, "Beside opencv-python"): only while it calls no
    highgui window function, which the headless wheels lack."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    window = re.compile(r"cv2\.(imshow|namedWindow|waitKey|destroy\w*Window\w*|selectROI"
                        r"|createTrackbar|setMouseCallback|moveWindow|resizeWindow)\b")
    used = [f"{path.relative_to(root)}: {m.group(0)}"
            for folder in ("vsmatch", "scripts") for path in (root / folder).rglob("*.py")
            for m in window.finditer(path.read_text())]
    assert used == []
