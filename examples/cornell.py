#!/usr/bin/env python3
"""The Cornell box from Python, notebook style: load, mesh, form factors, two solvers, plot.

    PYTHONPATH=build/python /usr/bin/python3 examples/cornell.py [-o DIR] [--patches N]

Writes DIR/cornell_convergence.png (residual vs iteration and vs time of both solvers) and
DIR/cornell.png (the rendered solution), and prints what each solver did.
"""
import argparse
import os
import time

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import lambert  # noqa: E402

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-o", "--output", default=".", help="directory for the figures")
parser.add_argument("--patches", type=int, default=500)
args = parser.parse_args()
os.makedirs(args.output, exist_ok=True)

# 1. The scene and its mesh (numpy views of the patches).
scene = lambert.load_scene()  # None: the built-in Cornell box
mesh = scene.mesh(patches=args.patches)
print(f"{scene.source}: {len(scene.surfaces)} surfaces, {len(mesh)} patches, "
      f"total area {mesh.areas.sum():.4g}")

# 2. Form factors: F (a scipy.sparse.csr_matrix), the per-entry standard errors and the
#    settings that made them.
t0 = time.perf_counter()
ff = lambert.form_factors(mesh, estimator="hybrid", samples=16, seed=1, stderr=True)
F, S = ff.matrix, ff.stderr
print(f"F: {F.nnz} entries in {time.perf_counter() - t0:.2f} s, row sums "
      f"{F.sum(axis=1).min():.4f}..{F.sum(axis=1).max():.4f}, median standard error "
      f"{np.median(S.data):.2e}")

# 3. Two solvers on the same F.
results = {}
for solver in ("jacobi", "gauss-seidel"):
    B, report = lambert.solve(mesh, F, solver=solver, tol=1e-10)
    results[solver] = (B, report)
    print(f"{solver:>12}: {report['status']}, {report['iterations']} iterations, residual "
          f"{report['residual']:.2e}, {report['seconds'] * 1e3:.1f} ms, energy imbalance "
          f"{max(e['relative_imbalance'] for e in report['energy']):.2e}")
B1, B2 = (results[s][0] for s in results)
print(f"max |B_jacobi - B_gauss-seidel| = {np.abs(B1 - B2).max():.3e}")

# 4. Convergence plot (channel R; every channel is in report['channels']).
fig, (ax_it, ax_t) = plt.subplots(1, 2, figsize=(11, 4))
for solver, (_, report) in results.items():
    ch = report["channels"][0]
    ax_it.semilogy(ch["history_iteration"], ch["residual_history"], marker=".", label=solver)
    ax_t.semilogy(ch["time_history"], ch["residual_history"], marker=".", label=solver)
ax_it.set(title="residual vs iteration (R)", xlabel="iteration", ylabel="||E - K B|| / ||E||")
ax_t.set(title="residual vs time (R)", xlabel="seconds", ylabel="||E - K B|| / ||E||")
for ax in (ax_it, ax_t):
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
fig.tight_layout()
plot = os.path.join(args.output, "cornell_convergence.png")
fig.savefig(plot)
print(f"wrote {plot}")

# 5. The image (a numpy array; also written as a tone-mapped PNG).
image = lambert.render(mesh, B2, width=256, height=256, png=os.path.join(args.output, "cornell.png"))
print(f"rendered {image.shape}, wrote {os.path.join(args.output, 'cornell.png')}")
