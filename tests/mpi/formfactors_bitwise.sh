# F from K ranks is bitwise identical to the single-process F (docs/cluster.md "Running on a
# cluster"): the saved binary files are compared byte for byte (same header: mesh hash and
# settings; same rows, columns and doubles), for several rank counts, estimators and options.
source "$(dirname "$0")/common.sh"

check() {  # check NAME ARGS...: single-process (-j 1) vs 1, 2 and 3 ranks
  local name=$1
  shift
  "$lambert" formfactors -q -j 1 "$@" -o "$tmp/$name-serial.bin"
  for np in 1 2 3; do
    mpi "$np" formfactors --distributed -q "$@" -o "$tmp/$name-np$np.bin"
    cmp "$tmp/$name-serial.bin" "$tmp/$name-np$np.bin"
    echo "$name: -np $np identical"
  done
}
check hybrid --patches 150 --estimator hybrid --samples 8 --seed 7
# mc with per-entry standard errors (their doubles travel with the values) and a threshold
# (applied per pair, both entries together).
check mc-stderr --patches 120 --estimator mc --samples 8 --seed 3 --stderr --threshold 1e-4
# The report carries the distributed section: 2 ranks, rows covering 0..n.
python3 - "$tmp/hybrid-np2.report.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))["distributed"]
rows = d["rows"]
assert d["ranks"] == 2 and rows[0][0] == 0 and rows[0][1] == rows[1][0], d
assert len(d["peak_memory_bytes_per_rank"]) == 2 and d["exchange_bytes"] > 0, d
print("report:", d)
PY
