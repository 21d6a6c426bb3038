# The PETSc solve (docs/cluster.md):
#  1. Cornell box, 2 ranks: B agrees with the single-process `direct` solve on the same F
#     within tol ||E||_2 / (1 - rho_max) + the same bound for direct's own residual, per
#     channel. Why: with K = I - diag(rho) F and ||rho F||_inf <= rho_max < 1 (row sums of F
#     at most 1), ||K^-1||_inf <= 1 / (1 - rho_max), so ||B - B*||_inf <= ||r||_inf /
#     (1 - rho_max) <= ||r||_2 / (1 - rho_max), and the stopping rule is ||r||_2 <= tol ||E||_2.
#  2. A --petsc-options pass-through (BiCGStab, block Jacobi) meets the same bound and is reported.
#  3. The furnace (closed cube, rho = 0.5, E = 1 everywhere): B = E / (1 - rho) = 2, up to
#     the solver's tol ||E||_2 / (1 - rho) and F's row sums s_i in [s_min, 1] (hybrid's
#     quadrature): by monotonicity E / (1 - rho s_min) <= B* <= E / (1 - rho).
#  4. The energy balance is computed over the ranks: emitted = sum A E of the light.
#  5. run --distributed writes every output from rank 0 (below, before the furnace).
source "$(dirname "$0")/common.sh"

# 1-2: the same F for both (saved once, by 2 ranks, loaded by every run).
mpi 2 formfactors --distributed -q --patches 300 --estimator hybrid --samples 8 -o "$tmp/F.bin"
"$lambert" solve -q --ff "$tmp/F.bin" --patches 300 --solver direct -o "$tmp/direct.csv"
mpi 2 solve --distributed -q --ff "$tmp/F.bin" --patches 300 --tol 1e-8 -o "$tmp/petsc.csv"
mpi 2 solve --distributed -q --ff "$tmp/F.bin" --patches 300 --tol 1e-8 \
  --petsc-options "-ksp_type bcgs -pc_type bjacobi" -o "$tmp/bcgs.csv"
# The same without --ff: F computed over the ranks inside solve.
mpi 2 solve --distributed -q --patches 300 --estimator hybrid --samples 8 --tol 1e-8 \
  -o "$tmp/inline.csv"

python3 - "$tmp" "$data/cornell_box/cornell_box.mtl" <<'PY'
import csv, json, math, sys
tmp, mtl = sys.argv[1], sys.argv[2]
# rho_max and the light's E per channel from the scene's materials.
kd, ke, name = {}, {}, None
for line in open(mtl):
    w = line.split()
    if not w: continue
    if w[0] == "newmtl": name = w[1]
    if w[0] == "Kd": kd[name] = [float(x) for x in w[1:4]]
    if w[0] == "Ke": ke[name] = [float(x) for x in w[1:4]]
rho_max = [max(v[c] for v in kd.values()) for c in range(3)]
def rows(path):
    return list(csv.DictReader(open(path)))
direct = rows(f"{tmp}/direct.csv")
lights = [r for r in direct if r["surface"] == "light"]
assert lights, "no light patches in the CSV"
e_norm = [ke["light"][c] * math.sqrt(len(lights)) for c in range(3)]
d_sum = json.load(open(f"{tmp}/direct.json"))
for name, tol in (("petsc", 1e-8), ("bcgs", 1e-8), ("inline", 1e-8)):
    s = json.load(open(f"{tmp}/{name}.json"))
    assert s["solver"] == "petsc" and s["status"] == "converged", s["status"]
    got = rows(f"{tmp}/{name}.csv")
    for c, ch in enumerate("RGB"):
        rep = s["channels"][c]
        assert rep["residual"] <= tol, rep
        if name == "inline": continue  # its own F (same settings, so the same F: checked below)
        bound = (tol + d_sum["channels"][c]["residual"]) * e_norm[c] / (1 - rho_max[c])
        err = max(abs(float(a[ch]) - float(b[ch])) for a, b in zip(got, direct))
        print(f"{name} {ch}: max |B - B_direct| = {err:.3e} <= {bound:.3e}")
        assert err <= bound, (name, ch, err, bound)
    # Energy over the ranks: emitted is sum A E of the light patches.
    for c in range(3):
        emitted = sum(float(r["area"]) for r in lights) * ke["light"][c]
        got_e = s["channels"][c]["energy"]["emitted"]
        assert abs(got_e - emitted) <= 1e-12 * emitted * len(lights), (got_e, emitted)
    print(name, "distributed:", {k: s["distributed"][k] for k in ("ranks", "ksp_type", "pc_type")})
b = json.load(open(f"{tmp}/bcgs.json"))["distributed"]
assert b["ksp_type"] == "bcgs" and b["pc_type"] == "bjacobi", b
assert json.load(open(f"{tmp}/petsc.json"))["distributed"]["pc_type"] == "jacobi"
# Computing F inside solve over the ranks gives the same F as the saved one, hence the same B
# to the solver's rounding (both runs: the same PETSc method on the same matrix).
a, i = rows(f"{tmp}/petsc.csv"), rows(f"{tmp}/inline.csv")
assert all(x[ch] == y[ch] for x, y in zip(a, i) for ch in "RGB"), "inline F differs"
PY

# 5: run --distributed on the same F: rank 0 renders and writes every output; its per-surface
# averages (area-weighted means of B) are within the per-patch bound of 1 from `run` with
# direct on one process.
mpi 2 run --distributed -q --ff "$tmp/F.bin" --patches 300 --tol 1e-8 -o "$tmp/run-petsc"
"$lambert" run -q --ff "$tmp/F.bin" --patches 300 --solver direct -o "$tmp/run-direct"
python3 - "$tmp" "$data/cornell_box/cornell_box.mtl" <<'PY'
import json, math, os, sys
tmp, mtl = sys.argv[1], sys.argv[2]
kd, ke, name = {}, {}, None
for line in open(mtl):
    w = line.split()
    if w and w[0] == "newmtl": name = w[1]
    if w and w[0] == "Kd": kd[name] = [float(x) for x in w[1:4]]
    if w and w[0] == "Ke": ke[name] = [float(x) for x in w[1:4]]
p = json.load(open(f"{tmp}/run-petsc/report.json"))
d = json.load(open(f"{tmp}/run-direct/report.json"))
assert p["solver"]["name"] == "petsc" and p["solver"]["status"] == "converged", p["solver"]
assert p["distributed"]["ranks"] == 2
for f in p["files"]:
    assert os.path.getsize(f) > 0, f
lights = [s for s in d["surface_averages"] if s["name"] == "light"][0]["patches"]
for c in range(3):
    rho_max = max(v[c] for v in kd.values())
    e_norm = ke["light"][c] * math.sqrt(lights)
    bound = (1e-8 + d["solver"]["channels"][c]["residual"]) * e_norm / (1 - rho_max)
    for a, b in zip(p["surface_averages"], d["surface_averages"]):
        err = abs(a["average_radiosity"][c] - b["average_radiosity"][c])
        assert err <= bound, (a["name"], c, err, bound)
print("run --distributed: outputs written, surface averages within the bound")
PY

# 3: the furnace.
cat > "$tmp/furnace.mtl" <<'MTL'
newmtl wall
Kd 0.5 0.5 0.5
Ke 1 1 1
MTL
cat > "$tmp/furnace.obj" <<'OBJ'
mtllib furnace.mtl
usemtl wall
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 2 3 4
f 5 8 7 6
f 1 4 8 5
f 2 6 7 3
f 1 5 6 2
f 4 3 7 8
OBJ
mpi 2 formfactors --distributed -q "$tmp/furnace.obj" --patches 96 --estimator hybrid \
  --samples 4 -o "$tmp/furnace.bin"
mpi 2 solve --distributed -q "$tmp/furnace.obj" --patches 96 --ff "$tmp/furnace.bin" \
  --tol 1e-10 -o "$tmp/furnace.csv"
python3 - "$tmp" <<'PY'
import csv, json, math, sys
tmp = sys.argv[1]
rho, tol = 0.5, 1e-10
s_min = json.load(open(f"{tmp}/furnace.report.json"))["row_sums"]["min"]
b = list(csv.DictReader(open(f"{tmp}/furnace.csv")))
e_norm = math.sqrt(len(b))  # E = 1 on every patch
bound = tol * e_norm / (1 - rho) + (2 - 1 / (1 - rho * s_min))
err = max(abs(float(r[ch]) - 2.0) for r in b for ch in "RGB")
print(f"furnace: max |B - 2| = {err:.3e} <= {bound:.3e} (row sums >= {s_min:.9f})")
assert err <= bound, (err, bound)
PY
echo ok
