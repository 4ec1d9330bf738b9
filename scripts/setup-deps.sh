#!/usr/bin/env bash
# Installs the Debian packages polrig needs, only those missing; apt-get update runs once,
# and only when something is to be installed. Safe to run again.
set -euo pipefail

packages=(
  cmake g++ make git pkg-config
  clang libclang-rt-14-dev    # libFuzzer and its sanitizer runtimes (scripts/test.sh)
  libeigen3-dev libtbb-dev libyaml-cpp-dev libfmt-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libembree-dev libopenexr-dev
  liberfa-dev                 # the sun's apparent position (IAU SOFA-derived ERFA, as astropy)
  libgeographiclib-dev        # ins/: WGS-84 radii and normal gravity (GeographicLib, pkg-config)
  libhdf5-dev hdf5-tools       # sweep.h5 (serial HDF5 + its high-level dimension scales; h5dump to inspect it)
  libhwy-dev                  # Highway: the CS study's vectorised logarithms (src/vector_log.cpp)
  libopencv-dev               # the four cameras' geometric calibration (OpenCV's checkerboard corners and
                              # fisheye calibration: src/calib/four_camera_geometry.cpp, -DPOLRIG_OPENCV=ON);
                              # the only package with OpenCVConfig.cmake (calib3d-dev alone pulls nearly as much)
  libsleef-dev libxsimd-dev   # the other candidates in the vectorised-log benchmark (bench/ only)
  gnuplot-nox fonts-dejavu-core
  python3-dev pybind11-dev    # the Python module (docs/python.md)
  python3-numpy python3-pytest python3-matplotlib  # its arrays, its tests, its examples' plots
  python3-h5py                # the tests read sweep.h5 with an independent HDF5 reader
  python3-setuptools python3-wheel python3-pip python3-venv  # `pip install --no-build-isolation .`
                              # (pyproject.toml, setup.py) without PyPI, into a venv (its test)
  python3-nbconvert python3-ipykernel  # runs examples/polrig_tour.ipynb in its test
  libopenmpi-dev openmpi-bin  # -DPOLRIG_MPI=ON: sweeps across processes and machines (docs/scale.md)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} > 0)); then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "setup-deps: installing ${missing[*]}"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
fi
