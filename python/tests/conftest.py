"""Shared fixtures of the pytest suite: the repository, the polrig executable (for the
CLI-equality checks) and a CSV reader that keeps every double exactly."""
import csv
import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

# The sphere cache off for the module and the CLI runs (before polrig is imported): the suite
# never writes the user's ~/.cache, and every traced run solves, as the outputs it compares expect.
os.environ["POLRIG_CACHE_DIR"] = "off"


def polrig_exe() -> pathlib.Path:
    exe = os.environ.get("POLRIG_EXE")
    return pathlib.Path(exe) if exe else ROOT / "build" / "polrig"


def run_cli(*args, check=True):
    """Runs the polrig command (quiet) from the repository root; returns CompletedProcess."""
    cmd = [str(polrig_exe()), *map(str, args)]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr}")
    return p


def read_csv(path):
    """A CSV as {column: array}: numbers as float64 (Python's float() rounds correctly, as the
    writer's shortest form requires, so values compare bit for bit), other columns as str."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(header):
        cells = [r[j] for r in body]
        try:
            out[name] = np.array([float(c) for c in cells], dtype=np.float64)
        except ValueError:
            out[name] = np.array(cells, dtype=object)
    return out


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture
def cli():
    return run_cli
