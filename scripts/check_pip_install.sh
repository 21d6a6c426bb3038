#!/usr/bin/env bash
# Checks the pip route of docs/python.md: installs the package with `pip install .` into a
# fresh virtual environment (Debian's numpy and scipy visible, no network), then, from outside
# the source tree, imports it and runs the built-in Cornell box through form_factors and
# solve on the installed files. Exits non-zero on any failure. Not part of CI (it compiles
# the library once more, in build-pip/); run it after changing pyproject.toml or setup.py.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$(mktemp -d /tmp/lambert-venv.XXXXXX)
trap 'rm -rf "$venv"' EXIT
/usr/bin/python3 -m venv --system-site-packages "$venv"
"$venv/bin/pip" install -q --no-build-isolation --no-index "$root"
cd /tmp
"$venv/bin/python" - <<'PY'
import os, sys, lambert
assert lambert.__file__.startswith(sys.prefix), lambert.__file__  # the installed copy
mesh = lambert.load_scene().mesh(patches=200)
F = lambert.form_factors(mesh, estimator="hybrid", samples=8, seed=1)
B, report = lambert.solve(mesh, F)
assert report["status"] == "converged", report["status"]
print("check_pip_install: lambert", lambert.__version__, "from", os.path.dirname(lambert.__file__),
      "-", len(mesh.areas), "patches, solve", report["status"])
PY
