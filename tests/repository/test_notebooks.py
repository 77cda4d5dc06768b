"""Every notebook runs top to bottom in a fresh kernel from this environment, so none can rot,
and is committed executed, so a reader browsing the repository sees its results.

The notebooks check their own claims (``assert`` in their cells: the sources' tables to 0.01, the
couplers, the round trips), so executing them is the test. ``make notebooks`` executes them
in place (tests/support/notebooks.py).
"""

import nbformat
import pytest

from ..support.notebooks import NOTEBOOKS, execute

NAMES = (
    "crank_slotted_lever_lab",
    "scotch_yoke_shm",
    "drag_link_project",
    "textbook_examples",
    "synthesis_tour",
    "shaper_loads",
    "benchmark",
    "atlas",
)


def test_the_notebooks_are_the_ones_named():
    assert sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")) == sorted(NAMES)


def images(nb) -> int:
    return sum(
        "image/png" in o.get("data", {})
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.outputs
    )


@pytest.mark.parametrize("name", NAMES)
def test_a_notebook_is_committed_with_its_outputs(name):
    """Each code cell executed, in order, from one fresh run (``make notebooks``)."""
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    counts = [c.execution_count for c in nb.cells if c.cell_type == "code"]
    assert counts == list(range(1, len(counts) + 1)), f"{name}: run make notebooks"
    assert any(c.outputs for c in nb.cells if c.cell_type == "code"), name
    assert images(nb) or name == "textbook_examples", "every other notebook plots"


@pytest.mark.parametrize("name", NAMES)
def test_notebook_runs(name):
    nb = execute(name)
    assert images(nb) or name == "textbook_examples", "every other notebook plots"
