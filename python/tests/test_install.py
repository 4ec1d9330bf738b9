"""`cmake --install` puts the package where this python3 finds it, and the installed package
imports and works on its own (no build tree on the path)."""
import os
import pathlib
import subprocess
import sys

import pytest

from conftest import ROOT

BUILD = pathlib.Path(os.environ.get("POLRIG_BUILD_DIR", ROOT / "build"))
TARGET = os.environ.get("POLRIG_PYTHON_INSTALL_DIR")


@pytest.mark.skipif(TARGET is None, reason="run through CTest, which names the install folder")
def test_install_puts_the_package_on_this_pythons_path(tmp_path):
    assert TARGET in sys.path, f"{TARGET} is not on {sys.executable}'s sys.path"
    env = dict(os.environ, DESTDIR=str(tmp_path))
    subprocess.run(["cmake", "--install", str(BUILD)], check=True, env=env, capture_output=True)
    staged = tmp_path / TARGET.lstrip("/")
    assert (staged / "polrig" / "__init__.py").is_file()
    assert list((staged / "polrig").glob("_polrig*.so"))
    assert (staged / "polrig" / "_polrig.pyi").is_file()
    # The staged copy alone: the build tree's python/ is not on the path.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(staged)
    out = subprocess.run(
        [sys.executable, "-c",
         "import polrig; print(polrig.__file__); print(polrig.Rig()['eccentricity.L_IS'])"],
        check=True, env=env, capture_output=True, text=True, cwd=tmp_path).stdout.split()
    assert out[0].startswith(str(staged)) and float(out[1]) == 0.05
