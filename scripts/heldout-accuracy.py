#!/usr/bin/env python3
# Held-out accuracy of a calibration of the default rig (docs/validation.md): the rig simulated
# with N fresh noise seeds, its CS voltages (stops 180° apart averaged) turned into angles by
# `polrig apply` with PARAMS; prints the mean θ_sec accuracy ½(max − min) of the error curve.
# Usage (from the repository root): python3 scripts/heldout-accuracy.py POLRIG PARAMS N
import csv
import os
import statistics
import subprocess
import sys
import tempfile

exe, params, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
accuracies = []
with tempfile.TemporaryDirectory() as tmp:
    for s in range(n):
        sim = os.path.join(tmp, f"sim{s}")
        subprocess.run([exe, "simulate", "rigs/wang2019-indoor.yaml", "--set", f"seed={1000 + s}",
                        "-o", sim, "--no-plots"], check=True, capture_output=True)
        stops = {round(float(r["theta_R_deg"])): r for r in csv.DictReader(open(f"{sim}/stops.csv"))}
        cs_csv = os.path.join(tmp, f"cs{s}.csv")
        with open(cs_csv, "w") as f:
            f.write("theta_R_deg,V1,V2,V3\n")
            for t in range(0, 190, 10):
                a, b = stops[t], stops[t + 180]
                f.write(f"{t}," + ",".join(repr((float(a[f"V{i}"]) + float(b[f"V{i}"])) / 2)
                                           for i in (1, 2, 3)) + "\n")
        app = os.path.join(tmp, f"app{s}")
        subprocess.run([exe, "apply", params, cs_csv, "-o", app, "--no-plots"], check=True,
                       capture_output=True)
        e = [float(r["error_deg"]) for r in csv.DictReader(open(f"{app}/angles.csv"))]
        accuracies.append((max(e) - min(e)) / 2)
mean = statistics.mean(accuracies)
se = statistics.stdev(accuracies) / n ** 0.5
print(f"held-out theta_sec accuracy over {n} fresh seeds: mean {mean:.5f} deg ± {se:.5f} (SE), "
      f"median {statistics.median(accuracies):.5f}")
