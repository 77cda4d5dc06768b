"""The repository stands on its own: a user has it and nothing else. Every relative link in the
README and docs/ points at a file in it, and no shipped text names a path of the machine it
was written on or the project's private working files."""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# written split so that this file does not match itself
FORBIDDEN = [
    re.compile(r"\.\./" + "shared"),
    re.compile(r"\b" + "shared/(design|seeds)"),
    re.compile("/" + r"work/"),
    re.compile(r"(?i)seeds?[ _]?0\d\d(?!\d)"),  # in words and inside names alike
    re.compile(r"\b0\d\d_[0-9a-f]{16}\.txt\b"),
]


def shipped() -> list[Path]:
    files = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return [
        ROOT / f
        for f in sorted(set(files))
        if not f.startswith("benchmarks/results/")
        and (ROOT / f).is_file()
        and f != "tests/repository/test_self_contained.py"
        and Path(f).suffix in {".py", ".md", ".ipynb", ".toml", ".cfg", ""}
    ]


@pytest.mark.parametrize("path", shipped(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_text_points_outside_the_repository(path):
    text = path.read_text(errors="replace")
    for pattern in FORBIDDEN:
        hit = pattern.search(text)
        assert hit is None, f"{path.name}: {hit.group(0)!r}"


def test_every_relative_link_in_the_docs_resolves():
    for md in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for target in re.findall(r"\]\(([^)#\s]+)", md.read_text()):
            if re.match(r"[a-z]+:", target):
                continue  # a URL
            resolved = (md.parent / target).resolve()
            assert resolved.is_relative_to(ROOT) and resolved.exists(), f"{md.name}: {target}"
