#!/usr/bin/env python3
# Issue #13's thread criteria for a scenario's stages, measured the one way that holds on a
# noisy VM (docs/performance.md "Threads on a shared machine", "The stages, default against one
# thread, in one command"): `rendulic run` with the default threads and with `--threads 1`,
# idle and beside a busy process, in alternated rounds (the order of the two settings swapped
# every round), each stage's wall seconds read from the results' /timings. Per stage it prints
# the medians of both settings and the median and largest of the rounds' ratios default / one
# thread, and two verdicts: beside the busy process no stage above 1.25x of one thread (stages
# under 1 s are flagged: a single time slice is a few per cent of them), and idle the DEM
# stages (prepare to states) together at least 1.5x faster with the default.
#
#   python3 bench/stage_threads.py build/rendulic                      # quick.toml's DEM stages
#   python3 bench/stage_threads.py build/rendulic --rounds 4 --stages all --json out.json
#
# The busy process is a shell loop started before each loaded pair and stopped after it, as
# `rendulic bench --load` does for the engine's step. Needs h5py. Exit 2 with one line on
# stderr when a run fails or an argument is wrong.
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

import h5py

DEM_STAGES = ["prepare", "isotropic", "path", "states"]
LOADED_BOUND = 1.25  # issue #13: default at most this much slower than one thread, loaded
IDLE_GAIN = 1.5  # issue #13: the DEM stages together at least this much faster idle, default
SHORT = 1.0  # seconds: below this a stage's ratio is mostly scheduling noise


def fail(message):
    print(f"stage_threads: {message}", file=sys.stderr)
    sys.exit(2)


def start_busy(out):
    # Its own process group, so that stopping it stops the shell's loop and nothing else; named
    # after the runs' folder in `ps`, so that a check can tell it from other busy loops.
    return subprocess.Popen(
        ["sh", "-c", "while :; do :; done", f"rendulic-busy {out}"],
        start_new_session=True,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def stop_busy(busy):
    if busy is not None and busy.poll() is None:
        os.killpg(busy.pid, 9)
        busy.wait()


def run_once(rendulic, scenario, stages, sets, threads, out):
    cmd = [rendulic, "run", scenario, "--out", out, "--quiet"]
    if threads:
        cmd += ["--threads", str(threads)]
    if stages is not None:
        cmd += ["--set", "run.stages=[" + ",".join(f'"{s}"' for s in stages) + "]"]
    cmd += ["--set", "report.figures=false"]
    for s in sets:
        cmd += ["--set", s]
    start = time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - start
    if r.returncode != 0:
        lines = [x for x in r.stderr.splitlines() if x.strip()]
        fail(f"`{' '.join(cmd)}` exited {r.returncode}: {lines[-1] if lines else '(no message)'}")
    with h5py.File(os.path.join(out, "results.h5"), "r") as f:
        t = {k: float(v) for k, v in f["/timings"].attrs.items()}
        # The stages in the order they ran: the effective scenario the run stored.
        text = f.attrs["scenario"]
        order = tomllib.loads(text.decode() if isinstance(text, bytes) else text)["run"]["stages"]
    return {s: t[s] for s in order if s in t}, wall


def summed(runs, stages):
    """Per run, the seconds of `stages` together."""
    return [sum(t[s] for s in stages) for t in runs]


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, as every refusal here
        fail(message)


def main():
    ap = Parser(description="Issue #13's thread criteria per stage (docs/performance.md).")
    ap.add_argument("rendulic", help="the rendulic binary")
    ap.add_argument("--scenario", default=None, help="scenario file (default: quick.toml)")
    ap.add_argument("--rounds", type=int, default=3, help="alternated rounds (default 3)")
    ap.add_argument(
        "--stages",
        default=",".join(DEM_STAGES),
        help="comma-separated stages, or 'all' for the scenario's own (default: the DEM stages)",
    )
    ap.add_argument("--set", action="append", default=[], help="a scenario key, KEY=VALUE")
    ap.add_argument("--no-load", action="store_true", help="idle rounds only")
    ap.add_argument("--out", default=None, help="keep the runs in this folder")
    ap.add_argument("--json", default=None, help="also write the rows to this JSON file")
    a = ap.parse_args()

    if not (shutil.which(a.rendulic) or os.access(a.rendulic, os.X_OK)):
        fail(f"no executable rendulic at '{a.rendulic}'")
    if a.scenario is None:
        here = os.path.dirname(os.path.abspath(__file__))
        a.scenario = os.path.join(here, "..", "data", "scenarios", "quick.toml")
    if not os.path.isfile(a.scenario):
        fail(f"no scenario file '{a.scenario}'")
    if a.rounds < 1:
        fail(f"--rounds must be at least 1, not {a.rounds}")
    stages = None if a.stages == "all" else [s for s in a.stages.split(",") if s]
    if stages is not None and not stages:
        fail("--stages names no stage")

    out = a.out or tempfile.mkdtemp(prefix="rendulic-stage-threads-")
    os.makedirs(out, exist_ok=True)
    conditions = ["idle"] if a.no_load else ["idle", "loaded"]
    times = {c: {0: [], 1: []} for c in conditions}  # condition -> threads -> [timings]
    busy = None
    try:
        for k in range(a.rounds):
            for c in conditions:
                order = [0, 1] if k % 2 == 0 else [1, 0]
                busy = start_busy(out) if c == "loaded" else None
                for threads in order:
                    d = os.path.join(out, f"r{k}-{c}-{'default' if threads == 0 else 'one'}")
                    t, wall = run_once(a.rendulic, a.scenario, stages, a.set, threads, d)
                    times[c][threads].append(t)
                    print(
                        f"round {k + 1}/{a.rounds} {c:6} "
                        f"{'default' if threads == 0 else 'one thread':10} {wall:8.2f} s wall",
                        file=sys.stderr,
                    )
                stop_busy(busy)
                busy = None
    finally:
        stop_busy(busy)
        if a.out is None:
            shutil.rmtree(out, ignore_errors=True)

    rows = []
    verdicts = []
    for c in conditions:
        names = [s for s in times[c][0][0] if s in times[c][1][0]]
        if stages is not None:
            names = [s for s in stages if s in names]
        print(f"\n{c}: wall seconds per stage, median over {a.rounds} round(s)")
        print(f"{'stage':16} {'default':>9} {'one':>9} {'ratio median':>13} {'ratio max':>10}")
        for s in names + ["(sum)"]:
            d, o = (summed(times[c][th], names if s == "(sum)" else [s]) for th in (0, 1))
            ratios = [x / y for x, y in zip(d, o) if y > 0]
            row = {
                "condition": c,
                "stage": s,
                "default_s": d,
                "one_thread_s": o,
                "ratio_median": statistics.median(ratios) if ratios else None,
                "ratio_max": max(ratios) if ratios else None,
                "short": statistics.median(o) < SHORT,
            }
            rows.append(row)
            rm = f"{row['ratio_median']:.2f}" if ratios else "-"
            rx = f"{row['ratio_max']:.2f}" if ratios else "-"
            flag = "  (short)" if row["short"] else ""
            print(
                f"{s:16} {statistics.median(d):9.2f} {statistics.median(o):9.2f} "
                f"{rm:>13} {rx:>10}{flag}"
            )
        if c == "loaded":
            worst = [r for r in rows if r["condition"] == c and r["stage"] != "(sum)"]
            worst = [r for r in worst if r["ratio_median"] is not None]
            long_ = [r for r in worst if not r["short"]]
            which = f"of {SHORT:g} s or more" if long_ else f"(each shorter than {SHORT:g} s)"
            w = max(long_ or worst, key=lambda r: r["ratio_median"])
            ok = w["ratio_median"] <= LOADED_BOUND
            verdicts.append(
                f"loaded: worst stage {which} {w['stage']} at {w['ratio_median']:.2f}x "
                f"of one thread (median of rounds): {'meets' if ok else 'misses'} "
                f"<= {LOADED_BOUND}x"
            )
        else:
            # The criterion is about the DEM stages; without any of them, the stages measured.
            dem = [s for s in names if s in DEM_STAGES] or names
            d, o = (summed(times[c][th], dem) for th in (0, 1))
            gain = statistics.median([y / x for x, y in zip(d, o) if x > 0])
            ok = gain >= IDLE_GAIN
            verdicts.append(
                f"idle: {', '.join(dem)} together {gain:.2f}x faster with the default "
                f"(median of rounds): {'meets' if ok else 'misses'} >= {IDLE_GAIN}x"
            )
    print()
    for v in verdicts:
        print(v)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
