#!/usr/bin/env bash
# Builds the `asan` preset (clang, AddressSanitizer + UBSan, the parsers of io/ instrumented
# with fuzzer-no-link; it holds the sanitizer tests and the libFuzzer targets) into build-asan/
# and runs each fuzz target for SECONDS (default 30), starting from its seed corpus in
# tests/fuzz/seeds/<parser>/ and growing a working corpus in build-asan/corpus/<target>/.
# Two lanes run side by side (one per core of the CI machine): obj_fuzz, the slowest per input
# (~6k executions/s under the sanitizers, so it needs the most time), for SECONDS x (the other
# targets), while the other lane runs every other target for SECONDS each: both lanes end
# together (at SECONDS = 20: 140 s, about 8 x 10^5 executions with the other lane busy).
# Exits non-zero if a target crashes (the reproducer is written to build-asan/crashes/).
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (named targets run one after another)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-30}"
shift || true
targets=("$@")
others=(ff_fuzz csv_fuzz camera_fuzz medium_fuzz stl_fuzz ply_fuzz heat_fuzz python_args_fuzz)

scripts/setup.sh asan >/dev/null
mkdir -p build-asan/crashes

fuzz() {  # fuzz TARGET SECONDS: runs it, prints its statistics; non-zero on a failure
  local t="$1" secs="$2" parser="${1%_fuzz}"
  local corpus="build-asan/corpus/$t"
  mkdir -p "$corpus"
  local dict=()
  [[ -f "tests/fuzz/$parser.dict" ]] && dict=(-dict="tests/fuzz/$parser.dict")
  echo "fuzz: $t for ${secs}s" >&2
  local status=0
  "build-asan/bin/$t" -max_total_time="$secs" -print_final_stats=1 -rss_limit_mb=2048 \
    -timeout=10 -max_len=65536 -artifact_prefix="build-asan/crashes/$t-" "${dict[@]}" \
    "$corpus" "tests/fuzz/seeds/$parser" 2> "build-asan/$t.log" || status=1
  ((status == 0)) || echo "fuzz: $t FAILED (see build-asan/$t.log and build-asan/crashes/)" >&2
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "build-asan/$t.log" |
    sed "s/^/fuzz: $t /" >&2 || true
  return $status
}

status=0
if ((${#targets[@]})); then
  for t in "${targets[@]}"; do fuzz "$t" "$seconds" || status=1; done
  exit $status
fi
fuzz obj_fuzz $((seconds * ${#others[@]})) &
obj=$!
for t in "${others[@]}"; do fuzz "$t" "$seconds" || status=1; done
wait "$obj" || status=1
exit $status
