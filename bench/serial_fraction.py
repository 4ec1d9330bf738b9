#!/usr/bin/env python3
"""Serial fraction of polrig's long commands (issue 25): each command run at 1 and at N threads
with POLRIG_STAGE_TIMES (docs/cli.md, "Environment"), which logs every progress stage's wall and
CPU time; the table says, per command, the one-thread time, the N-thread time, the speed-up and
the serial fraction f that Amdahl's law gives for it, f = (N·T_N/T_1 − 1)/(N − 1), and where the
serial time goes: the stage that loses most (its own T_N − T_1/N over T_1, ranked) and the time
outside every stage (start-up, reading, writing the outputs).

    python3 bench/serial_fraction.py [--polrig build/polrig] [--threads 2] [--only sweep,navigate]

Run it on an idle machine: another process on the cores reads as serial time. The one-thread run
is pinned to one core (taskset), since a command's writer thread (background_writer.h) would
otherwise overlap its output with one TBB thread. Inputs are made under a scratch folder (the
datasets the calibrations read are simulated first, untimed).
"""
import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time

# name, arguments after `polrig` ({d} the scratch folder), and an untimed set-up
COMMANDS = [
    ("sweep W19 1000 × 1000",
     "sweep rigs/wang2019-indoor.yaml --grid eccentricity.L_IS=0.001:1:1000 "
     "--grid eccentricity.alpha_S=0:359:1000", None),
    ("study cs W19 traced", "study cs rigs/wang2019-indoor-traced.yaml", None),
    ("simulate H17 indoor", "simulate rigs/han2017-indoor.yaml", None),
    ("calibrate H17 (dofp)", "calibrate {d}/h17 --method dofp",
     "simulate rigs/han2017-indoor.yaml -o {d}/h17"),
    ("simulate W16 rotation", "simulate rigs/wang2016-rotation.yaml", None),
    ("simulate W16 static hour", "simulate rigs/wang2016-static.yaml", None),
    ("locate W16 static hour", "locate {d}/w16", "simulate rigs/wang2016-static.yaml -o {d}/w16"),
    ("simulate Z21 static", "simulate rigs/zhang2021-static.yaml", None),
    ("navigate Z21 static", "navigate {d}/z21", "simulate rigs/zhang2021-static.yaml -o {d}/z21"),
    ("study navigation Z21 ×40", "study navigation rigs/zhang2021-static.yaml --trials 40", None),
]


def run(polrig, args, threads, scratch, log):
    out = os.path.join(scratch, "out")
    shutil.rmtree(out, ignore_errors=True)
    # The sphere cache off: a traced rig's first run would solve the sphere and the second load it.
    env = dict(os.environ, POLRIG_STAGE_TIMES=log, POLRIG_CACHE_DIR="off")
    cmd = [polrig] + args.split() + ["-o", out, "--threads", str(threads), "--quiet", "--force"]
    if threads == 1:  # one core, not one TBB thread: a writer thread would run beside it otherwise
        cmd = ["taskset", "-c", str(min(os.sched_getaffinity(0)))] + cmd
    if not args.startswith(("locate", "navigate")):
        cmd.append("--no-plots")
    t0 = time.monotonic()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.monotonic() - t0
    stages = {}
    total_cpu = None
    with open(log) as f:
        for row in csv.DictReader(f):
            if row["stage"] == "(total)":
                total_cpu = float(row["cpu_s"])
                continue
            w, c = stages.get(row["stage"], (0.0, 0.0))
            stages[row["stage"]] = (w + float(row["wall_s"]), c + float(row["cpu_s"]))
    return wall, total_cpu, stages


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--polrig", default="build/polrig")
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--only", default="", help="comma-separated words; a command runs if its name has one")
    a = p.parse_args()
    n = a.threads
    if n < 2:
        sys.exit("serial_fraction: needs at least 2 threads")
    words = [w for w in a.only.split(",") if w]
    print(f"| command | 1 thread | {n} threads | speed-up | serial fraction | stage losing most | outside stages |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="polrig-serial-") as scratch:
        log = os.path.join(scratch, "stages.csv")
        for name, args, setup in COMMANDS:
            if words and not any(w in name for w in words):
                continue
            if setup:
                subprocess.run([a.polrig] + setup.format(d=scratch).split() + ["--quiet", "--force", "--no-plots"],
                               check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, POLRIG_CACHE_DIR="off"))
            t1, _, s1 = run(a.polrig, args.format(d=scratch), 1, scratch, log)
            tn, _, sn = run(a.polrig, args.format(d=scratch), n, scratch, log)
            f = (n * tn / t1 - 1) / (n - 1)
            loss = {k: (sn[k][0] - s1[k][0] / n) / t1 for k in s1 if k in sn}
            worst = max(loss, key=loss.get) if loss else "—"
            outside = (tn - sum(w for w, _ in sn.values())) / t1
            worst_text = f"{worst} ({100 * loss[worst]:.1f} %)" if loss else "—"
            print(f"| {name} | {t1:.2f} s | {tn:.2f} s | {t1 / tn:.2f}× | {100 * f:.1f} % | {worst_text} | "
                  f"{100 * outside:.1f} % |", flush=True)


if __name__ == "__main__":
    main()
