#!/usr/bin/env bash
# Builds the `asan` preset (clang, AddressSanitizer + UBSan, the parsers of io/ instrumented
# with fuzzer-no-link; it holds the sanitizer tests and the libFuzzer targets) into build-asan/
# and runs each fuzz target for SECONDS (default 30), starting from its seed corpus in
# tests/fuzz/seeds/<parser>/ and growing a working corpus in build-asan/corpus/<target>/.
# Exits non-zero if a target crashes (the reproducer is written to build-asan/crashes/).
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-30}"
shift || true
targets=("$@")
((${#targets[@]})) || targets=(obj_fuzz ff_fuzz csv_fuzz camera_fuzz medium_fuzz stl_fuzz heat_fuzz)

scripts/setup.sh asan >/dev/null
mkdir -p build-asan/crashes
status=0
for t in "${targets[@]}"; do
  parser="${t%_fuzz}"
  corpus="build-asan/corpus/$t"
  mkdir -p "$corpus"
  dict=()
  [[ -f "tests/fuzz/$parser.dict" ]] && dict=(-dict="tests/fuzz/$parser.dict")
  echo "fuzz: $t for ${seconds}s" >&2
  if ! "build-asan/bin/$t" -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=2048 \
       -timeout=10 -max_len=65536 -artifact_prefix="build-asan/crashes/$t-" "${dict[@]}" \
       "$corpus" "tests/fuzz/seeds/$parser" 2> "build-asan/$t.log"; then
    echo "fuzz: $t FAILED (see build-asan/$t.log and build-asan/crashes/)" >&2
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "build-asan/$t.log" | sed "s/^/fuzz: $t /" >&2 || true
done
exit $status
