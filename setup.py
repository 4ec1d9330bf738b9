"""`pip install .`: CMake builds the module (target polrig_python), setuptools makes the wheel of
python/polrig with it (docs/python.md §1). The version is CMakeLists.txt's project(VERSION).

Environment:
  POLRIG_CMAKE_BUILD_DIR  a CMake build folder whose module is packed as it is, built and not
                          rebuilt (as `cmake --install` does), e.g. `build`; default: a temporary
                          one, Release, without tests and benchmarks, deleted afterwards.
  CMAKE_ARGS              more arguments for the configure step (shell syntax).
  CMAKE_BUILD_PARALLEL_LEVEL  build jobs (default: the CPU count, at most 8).
"""
import atexit
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent
VERSION = re.search(r"project\(polrig\s+VERSION\s+([0-9.]+)",
                    (ROOT / "CMakeLists.txt").read_text()).group(1)

# setuptools' own build and egg-info folders in scratch space, so the source tree stays clean.
SCRATCH = tempfile.mkdtemp(prefix="polrig-pip-")
atexit.register(shutil.rmtree, SCRATCH, ignore_errors=True)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        given = os.environ.get("POLRIG_CMAKE_BUILD_DIR")
        # A given folder is packed as built (as `cmake --install` does): rebuilding the module alone
        # there would leave its other targets, such as the CLI, a git revision behind it.
        build = pathlib.Path(given).resolve() if given else self.cmake_build()

        # The module must be this interpreter's (a reused build folder may be another's).
        name = "_polrig" + sysconfig.get_config_var("EXT_SUFFIX")
        built = build / "python" / "polrig" / name
        if not built.is_file():
            found = sorted(p.name for p in built.parent.glob("_polrig*"))
            raise RuntimeError(f"{built} not found (found: {found}): build the polrig_python "
                               f"target there first, configured with "
                               f"-DPython3_EXECUTABLE={sys.executable}")
        dest = pathlib.Path(self.get_ext_fullpath(ext.name))
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, dest)

    @staticmethod
    def cmake_build():
        build = pathlib.Path(SCRATCH) / "cmake"
        args = ["-DCMAKE_BUILD_TYPE=Release", "-DPOLRIG_BUILD_TESTS=OFF", "-DPOLRIG_BUILD_BENCH=OFF",
                "-DPOLRIG_PYTHON=ON", f"-DPython3_EXECUTABLE={sys.executable}"]
        if shutil.which("ccache"):
            args.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        args += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), *args], check=True)
        jobs = [] if "CMAKE_BUILD_PARALLEL_LEVEL" in os.environ else ["-j", str(min(os.cpu_count() or 1, 8))]
        subprocess.run(["cmake", "--build", str(build), "--target", "polrig_python", *jobs], check=True)
        return build


setup(
    version=VERSION,
    ext_modules=[Extension("polrig._polrig", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": SCRATCH}, "egg_info": {"egg_base": SCRATCH}},
)
