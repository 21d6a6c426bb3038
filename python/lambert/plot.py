"""Figures from the CSV files the lambert CLI writes, drawn with matplotlib.

    python3 -m lambert.plot compare DIR    # DIR/compare_history.csv -> compare_convergence.png
    python3 -m lambert.plot accuracy DIR   # DIR/accuracy_table.csv  -> accuracy_error_vs_time.png

DIR is the directory (or file prefix, as the CLI's -o) the command wrote to. The figures are
the panels of the CLI's SVGs: residual vs iteration and vs time per channel (compare), and
the error of F, of the closed-form surface factor and of B against form-factor time
(accuracy). -o PATH writes the figure elsewhere; --format picks the file type (png, pdf,
svg...). Only the CSVs are read, so this module needs no compiled part.
"""

import argparse
import csv
import math
import os
import sys
from collections import OrderedDict

CHANNELS = ("R", "G", "B")


def _prefix(path, name):
    """The CLI's output prefix: DIR/name for a directory, else the prefix itself."""
    return os.path.join(path, name) if os.path.isdir(path) or path.endswith("/") else path


def _rows(path):
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: no such file (run the lambert command with -o first)")
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt
    return plt


def _finish(ax, legend):
    ax.grid(True, which="both", alpha=0.3)
    if legend:
        ax.legend(fontsize="small")


def _save(plt, fig, output):
    fig.tight_layout()
    fig.savefig(output)
    plt.close(fig)
    return output


def compare_history(prefix):
    """{channel: {solver: (iterations, seconds, residuals)}} from <prefix>_history.csv."""
    out = OrderedDict((c, OrderedDict()) for c in CHANNELS)
    for r in _rows(prefix + "_history.csv"):
        it, t, res = out[r["channel"]].setdefault(r["solver"], ([], [], []))
        it.append(_number(r["iteration"]))
        t.append(_number(r["seconds"]))
        res.append(_number(r["residual"]))
    return out


def plot_compare(path, output=None, fmt="png", channels=CHANNELS):
    """Convergence figure of `lambert compare -o path`: per channel, residual vs iteration and
    vs time (log residual). Returns the file written."""
    prefix = _prefix(path, "compare")
    history = compare_history(prefix)
    table = {r["solver"]: r for r in _rows(prefix + "_table.csv")} \
        if os.path.exists(prefix + "_table.csv") else {}
    plt = _pyplot()
    channels = [c for c in channels if history[c]]
    fig, axes = plt.subplots(len(channels), 2, figsize=(11, 4 * len(channels)), squeeze=False)
    for row, c in zip(axes, channels):
        for solver, (it, t, res) in history[c].items():
            status = table.get(solver, {}).get("status", "")
            label = f"{solver} ({status})" if status else solver
            row[0].semilogy(it, res, marker=".", label=label)
            row[1].semilogy(t, res, marker=".", label=label)
        row[0].set(title=f"residual vs iteration (channel {c})", xlabel="iteration",
                   ylabel="||E - K B|| / ||E||")
        row[1].set(title=f"residual vs time (channel {c})", xlabel="seconds",
                   ylabel="||E - K B|| / ||E||")
        for ax in row:
            _finish(ax, True)
    return _save(plt, fig, output or f"{prefix}_convergence.{fmt}")


def plot_accuracy(path, output=None, fmt="png"):
    """Error-vs-time figure of `lambert accuracy -o path` (log-log, one series per estimator
    family, the reference row left out). Returns the file written."""
    prefix = _prefix(path, "accuracy")
    rows = [r for r in _rows(prefix + "_table.csv") if r["setting"] != "reference"]
    panels = [("rms_abs_err", "RMS |F - F_ref| per patch pair vs time", "RMS abs error of F")]
    if any(math.isfinite(_number(r["F_exact_abs_err"])) for r in rows):
        panels.append(("F_exact_abs_err", "surface factor error vs time (closed form)",
                       "max |F_GH - exact|"))
    panels.append(("B_max_rel_diff", "max relative B difference per surface vs time",
                   "max |B - B_ref| / B_ref"))
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4.5), squeeze=False)
    for ax, (column, title, ylabel) in zip(axes[0], panels):
        series = OrderedDict()
        for r in rows:
            x, y = _number(r["seconds"]), _number(r[column])
            if x > 0 and y > 0:
                xs, ys, names = series.setdefault(r["estimator"], ([], [], []))
                xs.append(x)
                ys.append(y)
                names.append(r["setting"])
        for name, (xs, ys, settings) in series.items():
            ax.loglog(xs, ys, marker="o", label=name)
            for x, y, s in zip(xs, ys, settings):
                ax.annotate(s, (x, y), fontsize="x-small", xytext=(3, 3),
                            textcoords="offset points")
        ax.set(title=title, xlabel="form-factor time (s)", ylabel=ylabel)
        _finish(ax, bool(series))
    return _save(plt, fig, output or f"{prefix}_error_vs_time.{fmt}")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m lambert.plot", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=["compare", "accuracy"])
    parser.add_argument("path", help="the -o directory or prefix of the lambert command")
    parser.add_argument("-o", "--output", help="figure file (default: next to the CSVs)")
    parser.add_argument("--format", default="png", help="file type when -o is not given")
    args = parser.parse_args(argv)
    try:
        if args.command == "compare":
            written = plot_compare(args.path, args.output, args.format)
        else:
            written = plot_accuracy(args.path, args.output, args.format)
    except (OSError, KeyError, ValueError) as e:
        print(f"lambert.plot: {e}", file=sys.stderr)
        return 1
    print(f"wrote {written}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
