#!/usr/bin/python3
"""Python against C++, in one run (docs/python.md §8):

1. rig.study_cs(360) from Python against the C++ benchmark of the same study (BM_CsStudy:
   the default rig, 360 table angles), run now as build/bench/polrig_bench.
2. A 10⁶-point sweep from Python against `polrig sweep --no-plots` on the same grid: wall time
   and peak memory (max RSS) of each.

Usage, from the repository root after building polrig, polrig_bench and polrig_python:
  PYTHONPATH=build/python /usr/bin/python3 bench/python_study_cs.py [--rounds 3] [--sweep-steps 360] [--no-sweep]
"""
import argparse
import json
import pathlib
import resource
import subprocess
import sys
import tempfile
import time
import timeit

import numpy as np

import polrig

ROOT = pathlib.Path(__file__).resolve().parents[1]
BUILD = ROOT / "build"


def cpp_study_cs_ns():
    """BM_CsStudy's time per study, ns: the least of 5 repetitions of ~0.5 s (CPU time; the
    study runs on one thread)."""
    out = subprocess.run(
        [str(BUILD / "bench" / "polrig_bench"), "--benchmark_filter=^BM_CsStudy$",
         "--benchmark_format=json", "--benchmark_repetitions=5", "--benchmark_min_time=0.5"],
        check=True, capture_output=True, text=True).stdout
    runs = [b for b in json.loads(out)["benchmarks"] if b.get("run_type") == "iteration"]
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}[runs[0]["time_unit"]]
    return min(b["cpu_time"] * scale for b in runs)


def python_study_cs_ns(touch_arrays):
    """rig.study_cs(360) from Python, ns per call: the least of 5 repeats of ~0.5 s each
    (process CPU time, as the C++ benchmark's cpu_time). With touch_arrays, every result array
    is also made (deviations, summary)."""
    rig = polrig.Rig()

    def call():
        cs = rig.study_cs(360)
        if touch_arrays:
            cs.theta_R_deg, cs.deviations_mV, cs.summary

    call()
    n = max(1, int(0.5 / timeit.timeit(call, number=20) * 20))
    timer = timeit.Timer(call, timer=time.process_time)
    return min(timer.repeat(repeat=5, number=n)) / n * 1e9


def sweep_python(grid, steps):
    rig = polrig.Rig()
    t0 = time.perf_counter()
    res = rig.sweep(grid, steps=steps)
    t = time.perf_counter() - t0
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    nbytes = sum(a.nbytes for a in res.fields.values())
    return t, rss_mb, nbytes / 1e6, len(res)


def sweep_cli(grid, steps):
    """`polrig sweep --no-plots` on the default rig: wall time, max RSS (GNU time's %M: the
    process's own, not the Python parent's that ru_maxrss of a child would carry over) and the
    size of sweep.h5 (its default output)."""
    with tempfile.TemporaryDirectory() as tmp:
        args = ["/usr/bin/time", "-f", "%M", "-o", f"{tmp}/rss", str(BUILD / "polrig"), "sweep",
                str(ROOT / "rigs" / "wang2019-indoor.yaml"), "--steps", str(steps), "-o", f"{tmp}/sweep",
                "--no-plots", "--quiet"]
        for k, v in grid.items():
            args += ["--grid", f"{k}={v}"]
        t0 = time.perf_counter()
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
        t = time.perf_counter() - t0
        size_mb = (pathlib.Path(tmp) / "sweep" / "sweep.h5").stat().st_size / 1e6
        rss_mb = int(pathlib.Path(f"{tmp}/rss").read_text().split()[-1]) / 1024
    return t, rss_mb, size_mb


def cpp_sweep_points_per_s():
    """BM_Sweep_20k: the library's in-memory sweep (SweepResult), 20,000 points at 360 angles
    on all cores; grid points per second."""
    out = subprocess.run(
        [str(BUILD / "bench" / "polrig_bench"), "--benchmark_filter=^BM_Sweep_20k", "--benchmark_format=json"],
        check=True, capture_output=True, text=True).stdout
    return json.loads(out)["benchmarks"][0]["items_per_second"]


def python_sweep_20k_points_per_s():
    """BM_Sweep_20k's grid from Python: rig.sweep on the default rig, all cores."""
    rig = polrig.Rig()
    grid = {"eccentricity.L_S": "0.001:1:200", "eccentricity.L_IS": "0.001:1:100"}
    t = min(timeit.repeat(lambda: rig.sweep(grid, 360), number=1, repeat=3))
    return 20000 / t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sweep-steps", type=int, default=360, help="table angles per CS study of the sweep")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved C++/Python timing rounds")
    ap.add_argument("--no-sweep", action="store_true", help="only the study_cs comparison")
    a = ap.parse_args()

    # Interleaved rounds, the least time of each: other load on the machine slows both alike.
    cpp, py_call, py_all = float("inf"), float("inf"), float("inf")
    for _ in range(a.rounds):
        cpp = min(cpp, cpp_study_cs_ns())
        py_call = min(py_call, python_study_cs_ns(False))
        py_all = min(py_all, python_study_cs_ns(True))
    print(f"study cs, default rig, 360 angles (CPU time per study; least of {a.rounds} rounds):")
    print(f"  C++ BM_CsStudy                  {cpp / 1e3:9.2f} µs")
    print(f"  Python rig.study_cs(360)        {py_call / 1e3:9.2f} µs   ratio {py_call / cpp:.3f}")
    print(f"  ... and every result array made {py_all / 1e3:9.2f} µs   ratio {py_all / cpp:.3f}")
    if a.no_sweep:
        return
    cpp_rate, py_rate = 0.0, 0.0
    for _ in range(a.rounds):
        cpp_rate = max(cpp_rate, cpp_sweep_points_per_s())
        py_rate = max(py_rate, python_sweep_20k_points_per_s())
    print(f"sweep of BM_Sweep_20k's grid (20,000 points, 360 angles, all cores; best of {a.rounds} rounds):")
    print(f"  C++ BM_Sweep_20k     {cpp_rate:9.0f} points/s")
    print(f"  Python rig.sweep     {py_rate:9.0f} points/s   ratio of times {cpp_rate / py_rate:.3f}")
    grid = {"eccentricity.L_S": "0.001:1:1000", "eccentricity.alpha_S": "0:359:1000"}
    tp, rss_p, arrays_mb, points = sweep_python(grid, a.sweep_steps)
    tc, rss_c, csv_mb = sweep_cli(grid, a.sweep_steps)
    print(f"sweep of {points} points ({' × '.join(grid)}; steps={a.sweep_steps}; all cores; wall time):")
    print(f"  Python rig.sweep     {tp:8.2f} s  {points / tp:9.0f} points/s   max RSS {rss_p:6.1f} MB "
          f"(result arrays {arrays_mb:.1f} MB)")
    print(f"  polrig sweep         {tc:8.2f} s  {points / tc:9.0f} points/s   max RSS {rss_c:6.1f} MB "
          f"(sweep.h5 {csv_mb:.1f} MB)")


if __name__ == "__main__":
    sys.exit(main())
