"""examples/polrig_tour.ipynb runs from top to bottom in a Jupyter kernel (Debian's python3-nbconvert
and python3-ipykernel: the "python3" kernel, /usr/bin/python3) and draws its three figures."""
import pathlib

import nbformat
from nbclient import NotebookClient

import polrig
from conftest import ROOT

NOTEBOOK = ROOT / "examples" / "polrig_tour.ipynb"


def test_tour_notebook_runs(tmp_path, monkeypatch):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert not any(c.outputs or c.execution_count for c in code), "store the notebook without outputs"
    # The kernel finds the package this test imported and runs in a scratch folder.
    monkeypatch.setenv("PYTHONPATH", str(pathlib.Path(polrig.__file__).parents[1]))
    monkeypatch.delenv("MPLBACKEND", raising=False)
    NotebookClient(nb, kernel_name="python3", timeout=120,
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    figures = [o for c in code for o in c.outputs if "image/png" in o.get("data", {})]
    assert len(figures) == 3
    assert not list(tmp_path.iterdir()), "the notebook writes no files"
