"""The notebooks executed in place, outputs and all (``make notebooks``), as the repository
carries them; tests/repository/test_notebooks.py runs each again in a fresh kernel.

    python -m tests.support.notebooks [name ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


def execute(name: str) -> nbformat.NotebookNode:
    """The notebook ``name`` run top to bottom in a fresh kernel of this environment."""
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOKS)}}
    ).execute()
    return nb


if __name__ == "__main__":
    for name in sys.argv[1:] or sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")):
        print(f"running {name}", flush=True)
        nbformat.write(execute(name), NOTEBOOKS / f"{name}.ipynb")
