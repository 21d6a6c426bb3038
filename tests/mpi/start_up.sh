# Start-up (issue 36): a lambert that does not run --distributed never loads MPI or PETSc
# (they live in the module lambert_distributed.so, loaded on first use), and without the
# module --distributed fails with one line naming it, exit 1, and writes nothing.
source "$(dirname "$0")/common.sh"

# The dynamic loader lists every object it opens (LD_DEBUG=files) on stderr.
for args in "--version" "info --patches 20"; do
  # shellcheck disable=SC2086
  LD_DEBUG=files "$lambert" $args > /dev/null 2> "$tmp/ld"
  if grep -E "file=[^ ]*(libmpi|libpetsc|lambert_distributed)" "$tmp/ld"; then
    echo "lambert $args loaded MPI, PETSc or the module"; exit 1
  fi
  grep -q "file=[^ ]*libembree3" "$tmp/ld" || { echo "LD_DEBUG listed nothing"; exit 1; }
done

# --distributed loads the module (and with it MPI and PETSc): one rank, F written.
LD_DEBUG=files mpi 1 formfactors --distributed -q --patches 20 --samples 4 -o "$tmp/F.bin" \
  2> "$tmp/ld"
grep -q "file=[^ ]*lambert_distributed.so" "$tmp/ld" || { echo "the module was not loaded"; exit 1; }
[[ -s "$tmp/F.bin" ]] || { echo "no F from one rank"; exit 1; }

# A copy of the executable without its module.
mkdir "$tmp/alone"
cp "$lambert" "$tmp/alone/lambert"
set +e
"$tmp/alone/lambert" formfactors --distributed -q --patches 20 -o "$tmp/alone/F.bin" 2> "$tmp/err"
code=$?
set -e
cat "$tmp/err"
[[ $code -eq 1 ]] || { echo "without the module: exit $code, expected 1"; exit 1; }
[[ $(wc -l < "$tmp/err") -eq 1 ]] || { echo "not one line"; exit 1; }
grep -q "^lambert: --distributed needs its module: .*alone/lambert_distributed.so" "$tmp/err" ||
  { echo "the error does not name the module"; exit 1; }
[[ ! -e "$tmp/alone/F.bin" ]] || { echo "F was written"; exit 1; }
echo "start-up: no MPI until --distributed; a missing module is one line, exit 1"
