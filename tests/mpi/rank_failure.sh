# A rank that fails makes every rank exit with the same code and rank 0 print its error,
# without a hang (the timeout in mpi() bounds the test). Two real failures:
#  1. a bad scene on rank 1 only (mpirun's MPMD form gives the ranks different arguments):
#     exit 1, the loader's message prefixed "rank 1:" on stderr;
#  2. a usage error found after MPI started (gather is refused with --distributed): exit 2;
#  3. PETSc refusing --petsc-options in the solve stage: exit 2.
source "$(dirname "$0")/common.sh"

printf 'v 0 0 0\nv 1 0 0\nf 1 2 7\n' > "$tmp/bad.obj"  # a face with a vertex that is not there
set +e
timeout 240 "$mpirun" --oversubscribe -np 1 "$lambert" formfactors --distributed -q \
  --patches 50 -o "$tmp/F.bin" : -np 1 "$lambert" formfactors --distributed -q "$tmp/bad.obj" \
  --patches 50 -o "$tmp/F.bin" 2> "$tmp/err1"
code=$?
set -e
cat "$tmp/err1"
[[ $code -eq 1 ]] || { echo "bad scene on rank 1: exit $code, expected 1"; exit 1; }
grep -q "^lambert: rank 1: .*bad.obj" "$tmp/err1" || { echo "no rank-1 error from rank 0"; exit 1; }
[[ $(grep -c "^lambert:" "$tmp/err1") -eq 1 ]] || { echo "the error was printed more than once"; exit 1; }
[[ ! -e "$tmp/F.bin" ]] || { echo "F was written"; exit 1; }

set +e
mpi 2 formfactors --distributed -q --patches 50 --estimator gather -o "$tmp/F.bin" 2> "$tmp/err2"
code=$?
set -e
cat "$tmp/err2"
[[ $code -eq 2 ]] || { echo "gather: exit $code, expected 2"; exit 1; }
grep -q "^lambert: .*--distributed takes mc, hybrid or analytic" "$tmp/err2"
# 3. PETSc refuses an option (an unknown KSP type) on every rank: a usage error, exit 2.
set +e
mpi 2 solve --distributed -q --patches 50 --petsc-options "-ksp_type nonsense" \
  -o "$tmp/B.csv" 2> "$tmp/err3"
code=$?
set -e
cat "$tmp/err3"
[[ $code -eq 2 ]] || { echo "bad PETSc option: exit $code, expected 2"; exit 1; }
grep -q "^lambert: --petsc-options" "$tmp/err3"
echo "ok"
