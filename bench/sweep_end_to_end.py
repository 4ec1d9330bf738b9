#!/usr/bin/env python3
"""The issue's first target, measured in one run: the 10⁶-point cos⁴ sweep end to end (process
start to files on disk, plots included, default outputs) against the NumPy reference of the same
CS study on one core (bench/numpy_cs_reference.py), as points per second and their ratio (target
≥ 40×; issue 35: ≥ 15× on an AVX-512 machine, with HDF5 and with --csv); the 720,000-point sweep
with --csv against the same sweep writing sweep.h5 only (issue 35: within 1.3×; --no-plots, both
fsynced whole as every sweep is); and, from polrig_bench, BM_CsSummary against its roofline
BM_Reference_VectorLog_1080 (the study's 1080 logarithms alone).

    /usr/bin/python3 bench/sweep_end_to_end.py [--exe build/polrig] [--bench build/bench/polrig_bench]

The load average is printed: on a shared machine the numbers are lower bounds.
"""
import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
GRID = ["--grid", "eccentricity.L_IS=0.001:1:1000", "--grid", "eccentricity.alpha_S=0:359:1000"]
POINTS = 1000 * 1000


CSV_GRID = ["--grid", "eccentricity.L_IS=0.001:1:720", "--grid", "eccentricity.alpha_S=0:359:1000"]
CSV_POINTS = 720 * 1000


def polrig_sweep_rate(exe, grid=GRID, points=POINTS, extra=()):
    """Points/s of `polrig sweep` over the grid, from process start to exit (its output folder is
    renamed into place before it exits), with the sizes of what it wrote."""
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="polrig_e2e_"))
    out = tmp / "sweep"
    try:
        t0 = time.perf_counter()
        subprocess.run([str(exe), "sweep", "rigs/wang2019-indoor.yaml", *grid, *extra, "-o", str(out), "--quiet"],
                       cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        seconds = time.perf_counter() - t0
        files = {p.name: p.stat().st_size for p in sorted(out.iterdir()) if p.is_file()}
        return points / seconds, seconds, files
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def numpy_rate(points):
    """Points/s of the NumPy reference on one core, in its own process (it pins itself to one CPU)."""
    code = ("import sys; sys.path.insert(0, 'bench'); import numpy_cs_reference as r; "
            f"print(r.points_per_second({points}))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True, capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def roofline(bench):
    """BM_CsSummary and BM_Reference_VectorLog_1080 (items per CPU second, one thread) and
    BM_Sweep_20k (points per wall-clock second on all cores, no output) from one polrig_bench run."""
    out = subprocess.run([str(bench), "--benchmark_filter=^(BM_CsSummary|BM_Reference_VectorLog_1080|BM_Sweep_20k.*)$",
                          "--benchmark_format=json", "--benchmark_repetitions=3",
                          "--benchmark_report_aggregates_only=true"],
                         cwd=ROOT, check=True, capture_output=True, text=True)
    rates = {}
    for b in json.loads(out.stdout)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            rates[b["run_name"].split("/")[0]] = b["items_per_second"]
    return rates["BM_CsSummary"], rates["BM_Reference_VectorLog_1080"], rates["BM_Sweep_20k"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", default=str(ROOT / "build" / "polrig"))
    ap.add_argument("--bench", default=str(ROOT / "build" / "bench" / "polrig_bench"))
    ap.add_argument("--numpy-points", type=int, default=40000)
    a = ap.parse_args()

    print(f"cpus {os.cpu_count()}, load average before {os.getloadavg()[0]:.2f}")
    ref = numpy_rate(a.numpy_points)
    print(f"numpy reference (1 core, {a.numpy_points} points): {ref:12,.0f} points/s")
    rate, seconds, files = polrig_sweep_rate(a.exe)
    sizes = ", ".join(f"{k} {v / 1e6:.1f} MB" for k, v in files.items())
    print(f"polrig sweep (10^6 points, end to end):   {rate:12,.0f} points/s ({seconds:.2f} s; {sizes})")
    print(f"ratio: {rate / ref:.1f} x the NumPy reference (target >= 40 x)")
    h5_rate, h5_s, _ = polrig_sweep_rate(a.exe, CSV_GRID, CSV_POINTS, ["--no-plots"])
    csv_rate, csv_s, files = polrig_sweep_rate(a.exe, CSV_GRID, CSV_POINTS, ["--no-plots", "--csv"])
    print(f"polrig sweep (720,000 points, --no-plots): sweep.h5 only {h5_s:.2f} s, with --csv {csv_s:.2f} s "
          f"(sweep.csv {files.get('sweep.csv', 0) / 1e6:.0f} MB): {csv_s / h5_s:.2f} x (target <= 1.3 x); "
          f"with --csv {csv_rate / ref:.1f} x the NumPy reference")
    if pathlib.Path(a.bench).exists():
        cs, logs, study = roofline(a.bench)
        print(f"BM_CsSummary {cs:,.0f}/s, BM_Reference_VectorLog_1080 {logs:,.0f}/s: "
              f"the study runs at {cs / logs:.2f} of its vector-log roofline")
        print(f"the study alone on all cores, no output (BM_Sweep_20k): {study:,.0f} points/s, "
              f"{study / ref:.1f} x the NumPy reference")
    print(f"load average after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
