"""The examples under examples/ run as scripts and make what they say."""
import ast
import os
import pathlib
import re
import subprocess
import sys

import pytest

import polrig
from conftest import ROOT

# The package this test imported, for the scripts (which run in a scratch folder).
ENV = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(pathlib.Path(polrig.__file__).parents[1]))

EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(script, tmp_path):
    p = subprocess.run([sys.executable, str(script), str(tmp_path)], env=ENV, cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    # The output folder (also the working folder) holds what the docstring says, nothing else.
    documented = set(re.findall(r"\w+\.png", ast.get_docstring(ast.parse(script.read_text()))))
    assert documented, "the docstring names no plot"
    assert {f.name for f in tmp_path.iterdir()} == documented
    assert all((tmp_path / png).stat().st_size > 10_000 for png in documented)
    if script.name == "fig11_sweep.py":
        # docs/validation.md, Figs. 11–12: "ASD 0.29213–0.29283 mV over L_S: 0.24 % range".
        assert "0.29213–0.29283 mV" in p.stdout and "0.24 % range" in p.stdout, p.stdout
