#!/usr/bin/env python3
"""Per-stage parallel scaling of `lambert run` (issue 37): each stage's wall and CPU seconds
(report.json "timings") at -j 1 and -j N, medians of --repeats runs; the serial fraction f of
each stage from Amdahl's law, T_N = T_1 (f + (1 - f) / N), so f = (T_N / T_1 - 1/N) / (1 - 1/N)
(clipped to [0, 1]); and the predicted time and speed-up at --predict threads (16). Beside
it the "busy" serial fraction from the CPU accounting at -j N (the seconds with one thread
busy, busy_fraction below) and the prediction from it: on two vCPUs that share a core the
parallel part runs slower per thread, which Amdahl's f counts as serial.

    bench/stage_scaling.py [--lambert build/bin/lambert] [-N 2] [--repeats 3] [--predict 16]
                           [-- RUN ARGS ...]        (default: the built-in Cornell box)

The machine may be shared: the figures are medians, and f is only as good as T_1 and T_N are
steady (on a loaded machine T_N grows and f with it: an upper bound).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile


def timings(lambert, threads, run_args):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([lambert, "run", "-q", "-j", str(threads), "-o", out] + run_args,
                       check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "report.json")) as f:
            return json.load(f)["timings"]


def medians(lambert, threads, run_args, repeats):
    runs = [timings(lambert, threads, run_args) for _ in range(repeats)]
    return {stage: {k: statistics.median(r[stage][k] for r in runs) for k in ("wall", "cpu")}
            for stage in runs[0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lambert", default="build/bin/lambert")
    ap.add_argument("-N", type=int, default=os.cpu_count())
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--predict", type=int, default=16)
    ap.add_argument("run_args", nargs="*", help="arguments of lambert run (after --)")
    a = ap.parse_args()
    if a.N < 2:
        sys.exit("stage_scaling: -N must be at least 2")
    one = medians(a.lambert, 1, a.run_args, a.repeats)
    many = medians(a.lambert, a.N, a.run_args, a.repeats)
    p = a.predict
    print(f"lambert run {' '.join(a.run_args) or '(Cornell box)'}: medians of {a.repeats}")
    print(f"{'stage':<24}{'wall -j1':>10}{'wall -j' + str(a.N):>10}{'cpu/wall':>10}"
          f"{'serial f':>10}{'pred -j' + str(p):>10}{'busy f':>10}{'pred -j' + str(p):>10}")
    t1 = tn = tp = tb = 0.0
    for stage in one:
        if stage == "total":
            continue
        w1, wn, cn = one[stage]["wall"], many[stage]["wall"], many[stage]["cpu"]
        ratio = cn / wn if wn > 0 else 0.0
        f = min(1.0, max(0.0, (wn / w1 - 1 / a.N) / (1 - 1 / a.N))) if w1 > 0 else 1.0
        pred = w1 * (f + (1 - f) / p)
        fb = busy_fraction(w1, wn, cn, a.N)
        pred_b = w1 * (fb + (1 - fb) / p)
        t1, tn, tp, tb = t1 + w1, tn + wn, tp + pred, tb + pred_b
        print(f"{stage:<24}{w1:>10.3f}{wn:>10.3f}{ratio:>10.2f}{f:>10.3f}{pred:>10.3f}"
              f"{fb:>10.3f}{pred_b:>10.3f}")
    ft = min(1.0, max(0.0, (tn / t1 - 1 / a.N) / (1 - 1 / a.N)))
    fbt = busy_fraction(t1, tn, many["total"]["cpu"], a.N)
    print(f"{'total':<24}{t1:>10.3f}{tn:>10.3f}{many['total']['cpu'] / tn:>10.2f}{ft:>10.3f}"
          f"{tp:>10.3f}{fbt:>10.3f}{tb:>10.3f}")
    print(f"speed-up: {t1 / tn:.2f}x at -j{a.N}; predicted at -j{p}: {t1 / tp:.2f}x from the "
          f"wall times (Amdahl), {t1 / tb:.2f}x from the busy threads (the issue's target: "
          f">= 12x for the matrix run, >= 8x for --method hierarchical)")


def busy_fraction(w1, wn, cn, n):
    """The serial fraction from the CPU accounting at -jN: a stage that runs S seconds on one
    thread and the rest on all N has cpu = S + N (wall - S), so S = (N wall - cpu) / (N - 1);
    f = S / T_1. Unlike Amdahl's f from the wall times it does not count the parallel part's
    slower threads (two vCPUs sharing a core) as serial: the estimate for N real cores."""
    if w1 <= 0:
        return 1.0
    serial = max(0.0, (n * wn - cn) / (n - 1))
    return min(1.0, serial / w1)


if __name__ == "__main__":
    main()
