# Shared by the mpirun tests: arguments LAMBERT MPIRUN DATA_DIR, a temp folder, and mpi K
# ARGS... running K ranks of lambert (oversubscribed: CI has 2 cores; as root through
# OMPI_ALLOW_RUN_AS_ROOT*, set by ctest) under a timeout, so that a hang fails.
set -euo pipefail
lambert=$1
mpirun=$2
data=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi() {
  local np=$1
  shift
  timeout 240 "$mpirun" --oversubscribe -np "$np" "$lambert" "$@"
}
