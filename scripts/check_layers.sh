#!/usr/bin/env bash
# Checks the module dependency direction of STYLE.md:
#   core <- geometry <- io <- apps,  core <- solvers <- apps,  apps <- python (the bindings
#   sit on top, beside the CLI; nothing includes python/)
# and that third-party libraries stay at the edge (Embree in geometry/bvh.cpp, OpenEXR in
# io/*.cpp only, MPI and PETSc in apps/dist_*.cpp only). Exits 1 listing every violation.
set -uo pipefail
cd "$(dirname "$0")/.."
status=0
forbid() {  # forbid MODULE PATTERN WHY
  local hits
  hits=$(grep -rnE "#include [<\"]($2)" "$1" --include='*.hpp' --include='*.cpp' || true)
  if [[ -n "$hits" ]]; then echo "layering: $1 must not include $2 ($3):"; echo "$hits"; status=1; fi
}
forbid core "geometry/|solvers/|io/|apps/" "core is the foundation"
forbid geometry "solvers/|io/|apps/" "geometry sees core only"
forbid solvers "geometry/|io/|apps/" "solvers see a matrix, vectors and areas"
forbid io "solvers/|apps/" "io sits below apps"
for m in core geometry solvers io apps; do forbid $m "python/" "the Python bindings are the top layer"; done
hits=$(grep -rlE "#include [<\"]embree" core geometry solvers io apps python | grep -v '^geometry/bvh.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: Embree outside geometry/bvh.cpp: $hits"; status=1; }
hits=$(grep -rlE "#include [<\"](OpenEXR/|Imf)" core geometry solvers io apps python | grep -vE '^io/.*\.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: OpenEXR outside io/*.cpp: $hits"; status=1; }
hits=$(grep -rlE "#include [<\"](mpi\.h|petsc)" core geometry solvers io apps tests bench |
  grep -vE '^apps/dist_[a-z_]+\.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: MPI or PETSc outside apps/dist_*.cpp: $hits"; status=1; }
[[ $status -eq 0 ]] && echo "layering: ok"
exit $status
