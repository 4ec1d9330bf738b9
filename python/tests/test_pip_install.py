"""`pip install --no-build-isolation .` (pyproject.toml, setup.py) into a fresh venv: the wheel
holds the module and its stubs, and its python imports polrig from anywhere, with the version of
CMakeLists.txt. The module is the CTest build folder's (POLRIG_CMAKE_BUILD_DIR), packed as built:
only the wheel is new, and the build folder is left as it was."""
import json
import os
import pathlib
import re
import subprocess
import sys

import pytest

from conftest import ROOT

BUILD = os.environ.get("POLRIG_BUILD_DIR")
VERSION = re.search(r"project\(polrig\s+VERSION\s+([0-9.]+)",
                    (ROOT / "CMakeLists.txt").read_text()).group(1)

CHECK = """
import importlib.metadata, json, pathlib, polrig
pkg = pathlib.Path(polrig.__file__).parent
print(json.dumps({"file": polrig.__file__, "version": polrig.__version__,
                  "dist_version": importlib.metadata.version("polrig"),
                  "files": sorted(str(f) for f in importlib.metadata.files("polrig")),
                  "L_IS": polrig.Rig()["eccentricity.L_IS"]}))
"""


@pytest.mark.skipif(BUILD is None, reason="run through CTest, which names the build folder")
def test_pip_install_into_a_venv(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    py = venv / "bin" / "python"
    # Nothing of the build tree or the user's site on the path; no index (no PyPI here).
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "PIP_"))}
    env.update(PYTHONNOUSERSITE="1", PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1",
               POLRIG_CMAKE_BUILD_DIR=BUILD)
    modules = list(pathlib.Path(BUILD, "python", "polrig").glob("_polrig*.so"))
    before = [m.stat().st_mtime_ns for m in modules]
    p = subprocess.run([str(py), "-m", "pip", "install", "--no-build-isolation", str(ROOT)],
                       env=env, cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stdout[-4000:] + p.stderr[-4000:]
    assert [m.stat().st_mtime_ns for m in modules] == before, "pip rebuilt the CTest build's module"

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = subprocess.run([str(py), "-c", CHECK], env=env, cwd=elsewhere, check=True,
                         capture_output=True, text=True).stdout
    got = json.loads(out)
    assert pathlib.Path(got["file"]).is_relative_to(venv), got["file"]
    assert got["version"] == VERSION and got["dist_version"] == VERSION
    assert {"polrig/__init__.py", "polrig/_polrig.pyi", "polrig/py.typed"} <= set(got["files"])
    assert any(re.fullmatch(r"polrig/_polrig\..*\.so", f) for f in got["files"]), got["files"]
    assert got["L_IS"] == 0.05
