#!/usr/bin/env bash
# Checks the module dependency direction of STYLE.md:
#   core <- geometry <- io <- pipeline <- apps,  core <- solvers <- pipeline,  pipeline <- python
#   (the CLI in apps/ and the Python bindings are the two front ends over the pipeline: python/
#   never includes apps/, nothing includes python/, and CLI11 stays in apps/)
# and that third-party libraries stay at the edge (Embree in geometry/visibility/bvh.cpp, OpenEXR in
# io/*.cpp only, MPI and PETSc in apps/dist_*.cpp only). Exits 1 listing every violation.
set -uo pipefail
cd "$(dirname "$0")/.."
status=0
forbid() {  # forbid MODULE PATTERN WHY
  local hits
  hits=$(grep -rnE "#include [<\"]($2)" "$1" --include='*.hpp' --include='*.cpp' || true)
  if [[ -n "$hits" ]]; then echo "layering: $1 must not include $2 ($3):"; echo "$hits"; status=1; fi
}
forbid core "geometry/|solvers/|io/|pipeline/|apps/" "core is the foundation"
forbid geometry "solvers/|io/|pipeline/|apps/" "geometry sees core only"
forbid solvers "geometry/|io/|pipeline/|apps/" "solvers see a matrix, vectors and areas"
forbid io "solvers/|pipeline/|apps/" "io sits below the pipeline"
forbid pipeline "apps/|CLI/" "the pipeline serves every front end: no CLI in it"
forbid python "apps/|CLI/" "Python is a front end beside the CLI, over the pipeline"
for m in core geometry solvers io pipeline apps; do forbid $m "python/" "the Python bindings are the top layer"; done
hits=$(grep -rlE "#include [<\"]embree" core geometry solvers io pipeline apps python | grep -v '^geometry/visibility/bvh.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: Embree outside geometry/visibility/bvh.cpp: $hits"; status=1; }
hits=$(grep -rlE "#include [<\"](OpenEXR/|Imf)" core geometry solvers io pipeline apps python | grep -vE '^io/.*\.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: OpenEXR outside io/*.cpp: $hits"; status=1; }
hits=$(grep -rlE "#include [<\"](mpi\.h|petsc)" core geometry solvers io pipeline apps tests bench |
  grep -vE '^apps/dist_[a-z_]+\.cpp$' || true)
[[ -z "$hits" ]] || { echo "layering: MPI or PETSc outside apps/dist_*.cpp: $hits"; status=1; }
[[ $status -eq 0 ]] && echo "layering: ok"
exit $status
