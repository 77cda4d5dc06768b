"""House rules the code keeps, read from the source: synth's packages import only downwards,
no module uses another package's private names, no module of synth is longer than a reader
can hold, the formatter decides the layout but for a few tables, and every Markdown file the
tree names is in it."""

from __future__ import annotations

import ast
import importlib.util
import re
import subprocess
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("synth", "api", "benchmarks", "tests")
MAX_LINES = 450  # per module of synth
MAX_UNFORMATTED = 10  # places the formatter is told to leave alone (fmt: skip, fmt: off)


def private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def python_files(*tops: str) -> list[Path]:
    return sorted(
        p for top in tops for p in (ROOT / top).rglob("*.py") if "__pycache__" not in p.parts
    )


def module_of(path: Path) -> tuple[str, str]:
    """A file's dotted module name and the package it belongs to (an ``__init__.py`` belongs
    to the package it makes)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
        return ".".join(parts), ".".join(parts)
    return ".".join(parts), ".".join(parts[:-1])


@cache
def kind(dotted: str) -> str | None:
    """What a dotted name is: "package", "module", or None (an object in a module, or
    nothing)."""
    if dotted.split(".")[0] in PACKAGES:
        base = ROOT.joinpath(*dotted.split("."))
        if (base / "__init__.py").is_file():
            return "package"
        return "module" if base.with_suffix(".py").is_file() else None
    try:
        spec = importlib.util.find_spec(dotted)
    except (ImportError, ValueError, AttributeError):
        return None
    if spec is None:
        return None
    return "package" if spec.submodule_search_locations is not None else "module"


def owner_package(dotted: str) -> str | None:
    """The package whose name ``dotted`` is: that of its longest prefix that is a module."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        prefix = ".".join(parts[:n])
        k = kind(prefix)
        if k == "package":
            return prefix
        if k == "module":
            return ".".join(parts[: n - 1])
    return None


def crossing(dotted: str, package: str) -> str | None:
    """The owner of the first private name in ``dotted``, where it is not ``package``."""
    parts = dotted.split(".")
    for i, part in enumerate(parts):
        if private(part):
            owner = owner_package(".".join(parts[:i])) if i else None
            return owner if owner is not None and owner != package else None
    return None


def private_uses(path: Path) -> list[str]:
    """Each import of, or attribute read of, another package's private name in one file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    _, package = module_of(path)
    rel = path.relative_to(ROOT)
    bound: dict[str, str] = {}  # a name an import binds -> the dotted name it stands for
    found = []

    def report(node: ast.AST, dotted: str, how: str) -> None:
        owner = crossing(dotted, package)
        if owner is not None:
            found.append(
                f"{rel}:{node.lineno}: {how} {dotted} (private to {owner}, used from {package})"
            )

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                report(node, a.name, "imports")
                if a.asname:
                    bound[a.asname] = a.name
                else:
                    top = a.name.split(".")[0]
                    bound[top] = top
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                source = ".".join([*base, *([node.module] if node.module else [])])
            else:
                source = node.module or ""
            for a in node.names:
                if a.name == "*":
                    continue
                report(node, f"{source}.{a.name}", "imports")
                bound[a.asname or a.name] = f"{source}.{a.name}"

    def dotted(node: ast.AST) -> str | None:
        if isinstance(node, ast.Name):
            return bound.get(node.id)
        if isinstance(node, ast.Attribute):
            inner = dotted(node.value)
            return None if inner is None else f"{inner}.{node.attr}"
        return None

    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and private(node.attr):
            inner = dotted(node.value)
            if inner is not None and not any(private(p) for p in inner.split(".")):
                report(node, f"{inner}.{node.attr}", "reads")
    return found


def test_no_module_uses_another_packages_private_names():
    found = [line for p in python_files(*PACKAGES) for line in private_uses(p)]
    assert not found, "private names used across packages:\n" + "\n".join(found)


# synth's packages from the ground up (docs/architecture.md): a module imports from its own
# layer and those below it, never from one above
LAYERS = (
    ("synth.errors", "synth.targets", "synth.numerics", "synth.version", "synth.requests"),
    ("synth.results", "synth.load", "synth.objectives"),
    ("synth.mechanisms",),
    ("synth.analysis",),
    ("synth.drawing", "synth.synthesis"),
    ("synth.atlas",),
    ("synth",),
)


def layer(dotted: str) -> int:
    """The layer of a dotted name in synth: that of its longest prefix in ``LAYERS``."""
    best, at = -1, -1
    for i, names in enumerate(LAYERS):
        for n in names:
            if (dotted == n or dotted.startswith(n + ".")) and len(n) > best:
                best, at = len(n), i
    return at


def synth_imports(path: Path) -> list[tuple[int, str]]:
    """(line, dotted name) of each name of synth one file imports."""
    _, package = module_of(path)
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                source = ".".join([*base, *([node.module] if node.module else [])])
            else:
                source = node.module or ""
            out += [(node.lineno, f"{source}.{a.name}") for a in node.names]
    return [(line, name) for line, name in out if name.split(".")[0] == "synth"]


def test_synth_imports_only_downwards():
    found = []
    for p in python_files("synth"):
        here = layer(module_of(p)[0])
        for line, name in synth_imports(p):
            if layer(name) > here:
                found.append(f"{p.relative_to(ROOT)}:{line}: imports {name}, a layer above it")
    assert not found, "imports that run back up:\n" + "\n".join(found)


def test_the_import_graph_of_synth_has_no_cycle():
    """No module of synth imports, through others, itself: every import counts, those for the
    type checker and those inside functions too."""
    mods = {module_of(p)[0]: p for p in python_files("synth")}

    def owner(dotted: str) -> str | None:  # the module a dotted name is in
        parts = dotted.split(".")
        return next(
            (m for n in range(len(parts), 0, -1) if (m := ".".join(parts[:n])) in mods), None
        )

    graph = {
        name: {owner(d) for _, d in synth_imports(p)} - {name, None} for name, p in mods.items()
    }
    done: set[str] = set()

    def walk(name: str, path: list[str]) -> None:
        if name in path:
            raise AssertionError(
                "an import cycle: " + " → ".join([*path[path.index(name) :], name])
            )
        if name in done:
            return
        for other in sorted(graph[name]):  # type: ignore[type-var]
            walk(other, [*path, name])
        done.add(name)

    for name in sorted(mods):
        walk(name, [])


def test_no_module_of_synth_is_over_450_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in python_files("synth")
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"over {MAX_LINES} lines: {long}"


def test_the_formatter_decides_the_layout_but_in_a_few_places_each_with_its_reason():
    """At most ``MAX_UNFORMATTED`` places in the tree keep their own layout, each with a
    comment on the line before that says why."""
    places, bare = [], []
    for p in python_files(*PACKAGES):
        lines = p.read_text().splitlines()
        for i, line in enumerate(lines):
            if re.search(r"#\s*fmt:\s*(skip|off)", line):
                places.append(f"{p.relative_to(ROOT)}:{i + 1}")
                if i == 0 or not lines[i - 1].lstrip().startswith("#"):
                    bare.append(places[-1])
    assert len(places) <= MAX_UNFORMATTED, places
    assert not bare, f"no reason given: {bare}"


# a Markdown file's name: path characters ending in .md, not inside a longer path or a URL
MD_NAME = re.compile(r"(?<![\w./:-])([\w./-]*\w\.md)\b")
TEXT = {".py", ".md", ".ipynb", ".html", ".js", ".toml"}


def tree() -> list[str]:
    """The repository's files (tracked, and new ones not ignored), as paths from its root."""
    out = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return sorted({f for f in out.splitlines() if (ROOT / f).is_file()})


def test_every_markdown_file_named_is_in_the_repository():
    files = tree()
    names = {Path(f).name for f in files if f.endswith(".md")}
    missing = []
    for f in files:
        if not (Path(f).suffix in TEXT or f in {"Makefile", "Dockerfile", ".ci/run"}):
            continue
        for i, line in enumerate((ROOT / f).read_text(errors="replace").splitlines(), 1):
            for name in MD_NAME.findall(line):
                first = name.split("/")[0]
                if "/" in name and "." in first.strip("."):
                    continue  # a host name: a URL without its scheme
                where = [(ROOT / f).parent / name, ROOT / name]
                if any(p.resolve().is_file() for p in where):
                    continue
                if "/" not in name and name in names:
                    continue
                missing.append(f"{f}:{i}: {name}")
    assert not missing, "Markdown files named but not in the repository:\n" + "\n".join(missing)
