#!/usr/bin/env python3
"""Serial fraction of polrig's long commands (issue 25): each command run at 1 and at N threads
with POLRIG_STAGE_TIMES (docs/cli.md, "Environment"), which logs every progress stage's wall and
CPU time; the table says, per command, the one-thread time, the N-thread time, the speed-up and
the serial fraction f that Amdahl's law gives for it, f = (N·T_N/T_1 − 1)/(N − 1), and where the
serial time goes: the stage that loses most (its own T_N − T_1/N over T_1, ranked) and the time
outside every stage (start-up, reading, writing the outputs).

The same run's f (the issue's measure: the time in serial stages against the CPU time of the
parallel ones) comes from the N-thread run alone, so that no second run's noise enters it: the
run's cores idle N·T_N − CPU_N core-seconds, and a serial stage of s seconds idles (N − 1)·s of
them, so f = (N·T_N − CPU_N)/((N − 1)·CPU_N) (CPU_N ≈ T_1 when the threads add no work). The stage
that idles most is named with its share of that f.

    python3 bench/serial_fraction.py [--polrig build/polrig] [--threads 2] [--only sweep,navigate] [--corun]
                                     [--repeat 3]

--repeat K runs the one-thread and the N-thread runs K times each, alternately, and takes the
median of each: on a shared virtual machine one run's time moves by up to ±8 %, which on two
cores is ±16 % in f.

--corun also runs N copies of the one-thread run at once, each on its own core, and prints the
machine's own f for the command: what N independent one-thread runs lose to each other (shared
caches, memory bandwidth, the page cache) is a serial fraction no code change removes, and on a
small machine it is most of what the N-thread run loses.

Run it on an idle machine: another process on the cores reads as serial time. The one-thread run
is pinned to one core (taskset), so that no thread beside TBB's (the sweep's writer,
background_writer.h; OpenEXR's pool) overlaps with it. Inputs are made under a scratch folder (the
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
    # The static hour's first 2 minutes (the hour itself: docs/validation.md, "Datasets sized to
    # what users run")
    ("simulate W16 static 120 s", "simulate rigs/wang2016-static.yaml --set schedule.count=120", None),
    ("locate W16 static 120 s", "locate {d}/w16 --prior 29,113.5",
     "simulate rigs/wang2016-static.yaml --set schedule.count=120 -o {d}/w16"),
    ("simulate Z21 static", "simulate rigs/zhang2021-static.yaml", None),
    ("navigate Z21 static", "navigate {d}/z21", "simulate rigs/zhang2021-static.yaml -o {d}/z21"),
    ("study navigation Z21 ×40", "study navigation rigs/zhang2021-static.yaml --trials 40", None),
]


def command(polrig, args, threads, out, log, core=None):
    # The sphere cache off: a traced rig's first run would solve the sphere and the second load it.
    env = dict(os.environ, POLRIG_STAGE_TIMES=log, POLRIG_CACHE_DIR="off")
    # --no-plots: gnuplot runs as a child process, whose time is not the command's
    cmd = [polrig] + args.split() + ["-o", out, "--threads", str(threads), "--quiet", "--force", "--no-plots"]
    if core is not None:
        cmd = ["taskset", "-c", str(core)] + cmd
    return cmd, env


def corun(polrig, args, n, scratch):
    """The wall time of n one-thread runs at once, each on its own core."""
    cores = sorted(os.sched_getaffinity(0))[:n]
    procs = []
    t0 = time.monotonic()
    for k, core in enumerate(cores):
        out = os.path.join(scratch, f"corun{k}")
        shutil.rmtree(out, ignore_errors=True)
        cmd, env = command(polrig, args, 1, out, os.path.join(scratch, f"corun{k}.csv"), core)
        procs.append(subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL))
    for p in procs:
        if p.wait() != 0:
            sys.exit(f"serial_fraction: {args} failed in the co-run")
    wall = time.monotonic() - t0
    for k in range(len(cores)):
        shutil.rmtree(os.path.join(scratch, f"corun{k}"), ignore_errors=True)
    return wall


def run(polrig, args, threads, scratch, log):
    out = os.path.join(scratch, "out")
    shutil.rmtree(out, ignore_errors=True)
    # one core, not one TBB thread: a writer thread would run beside it otherwise
    cmd, env = command(polrig, args, threads, out, log, min(os.sched_getaffinity(0)) if threads == 1 else None)
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


def idle_fraction(n, wall, cpu, stages):
    """The same run's f, and the stage idling most with its share of f (None outside every stage)."""
    scale = (n - 1) * cpu
    f = (n * wall - cpu) / scale
    idle = {k: (n * w - c) / scale for k, (w, c) in stages.items()}
    idle[None] = f - sum(idle.values())
    worst = max(idle, key=idle.get)
    return f, worst, idle[worst]


def median_run(runs):
    """The run of median wall time (its stages with it)."""
    return sorted(runs, key=lambda r: r[0])[len(runs) // 2]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--polrig", default="build/polrig")
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--only", default="", help="comma-separated words; a command runs if its name has one")
    p.add_argument("--corun", action="store_true", help="also the machine's own f (N one-thread runs at once)")
    p.add_argument("--repeat", type=int, default=1, help="runs of each, alternately; the medians are used")
    a = p.parse_args()
    n = a.threads
    if n < 2:
        sys.exit("serial_fraction: needs at least 2 threads")
    words = [w for w in a.only.split(",") if w]
    extra = (" machine's own f |", "---|") if a.corun else ("", "")
    print(f"| command | 1 thread | {n} threads | speed-up | serial fraction | stage losing most | outside stages |"
          f" same run's f | stage idling most |{extra[0]}")
    print("|---|---|---|---|---|---|---|---|---|" + extra[1])
    with tempfile.TemporaryDirectory(prefix="polrig-serial-") as scratch:
        log = os.path.join(scratch, "stages.csv")
        for name, args, setup in COMMANDS:
            if words and not any(w in name for w in words):
                continue
            if setup:
                subprocess.run([a.polrig] + setup.format(d=scratch).split() + ["--quiet", "--force", "--no-plots"],
                               check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, POLRIG_CACHE_DIR="off"))
            ones, ns = [], []
            for _ in range(a.repeat):  # alternately, so that a slow spell of the machine hits both
                ones.append(run(a.polrig, args.format(d=scratch), 1, scratch, log))
                ns.append(run(a.polrig, args.format(d=scratch), n, scratch, log))
            t1, _, s1 = median_run(ones)
            tn, cn, sn = median_run(ns)
            f = (n * tn / t1 - 1) / (n - 1)
            loss = {k: (sn[k][0] - s1[k][0] / n) / t1 for k in s1 if k in sn}
            worst = max(loss, key=loss.get) if loss else "—"
            outside = (tn - sum(w for w, _ in sn.values())) / t1
            worst_text = f"{worst} ({100 * loss[worst]:.1f} %)" if loss else "—"
            fi, idler, share = idle_fraction(n, tn, cn, sn)
            idler_text = f"{idler or 'outside stages'} ({100 * share:.1f} %)"
            machine = ""
            if a.corun:  # n runs at once in T_c: as one run of n·T1 work taking T_c, Amdahl's f
                tc = corun(a.polrig, args.format(d=scratch), n, scratch)
                machine = f" {100 * (n * (tc / n) / t1 - 1) / (n - 1):.1f} % |"
            print(f"| {name} | {t1:.2f} s | {tn:.2f} s | {t1 / tn:.2f}× | {100 * f:.1f} % | {worst_text} | "
                  f"{100 * outside:.1f} % | {100 * fi:.1f} % | {idler_text} |{machine}", flush=True)


if __name__ == "__main__":
    main()
