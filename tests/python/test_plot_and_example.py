"""The matplotlib plotter on real CLI output, and the example script."""
import os
import subprocess
import sys

from conftest import run_cli

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "..", "examples", "cornell.py")
PNG = b"\x89PNG\r\n\x1a\n"


def python(*args):
    p = subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                       env=dict(os.environ, MPLBACKEND="Agg"))
    assert p.returncode == 0, p.stderr
    return p


def test_plot_compare_writes_png(tmp_path):
    out = f"{tmp_path}/"
    run_cli("compare", "--solvers", "jacobi,gauss-seidel,cg", "-q", "--patches", 150,
            "--samples", 4, "-o", out)
    python("-m", "lambert.plot", "compare", out)
    assert (tmp_path / "compare_convergence.png").read_bytes()[:8] == PNG
    python("-m", "lambert.plot", "compare", out, "-o", tmp_path / "c.pdf")
    assert (tmp_path / "c.pdf").read_bytes()[:4] == b"%PDF"


def test_plot_accuracy_writes_png(tmp_path):
    prefix = f"{tmp_path}/study"
    run_cli("accuracy", "--case", "perpendicular_squares", "--max-edge", 0.5, "-q",
            "--mc-samples", 4, "--hybrid-samples", 4, "--hemicube-res", 16, "-o", prefix)
    python("-m", "lambert.plot", "accuracy", prefix)
    assert (tmp_path / "study_error_vs_time.png").read_bytes()[:8] == PNG


def test_plot_names_a_missing_csv(tmp_path):
    p = subprocess.run([sys.executable, "-m", "lambert.plot", "compare", f"{tmp_path}/"],
                       capture_output=True, text=True)
    assert p.returncode == 1 and "compare_history.csv" in p.stderr


def test_example_runs_and_writes_its_plot(tmp_path):
    python(EXAMPLE, "--patches", 150, "-o", tmp_path)
    assert (tmp_path / "cornell_convergence.png").read_bytes()[:8] == PNG
