#!/usr/bin/env bash
# Checks that the C++ lines a commit changes are clang-formatted (.clang-format: Google base,
# 100 columns); untouched lines are not judged. Usage: scripts/check_format.sh [BASE]
# (default BASE: HEAD~1, i.e. the last commit; for a merge, its first parent: the whole
# merged branch). Exits 1 with the diff that clang-format wants when a changed line is off.
set -euo pipefail
cd "$(dirname "$0")/.."
base="${1:-HEAD~1}"
if ! git rev-parse -q --verify "$base^{commit}" >/dev/null; then
  echo "check_format: no base commit $base (a single-commit clone?): nothing to check" >&2
  exit 0
fi
# git clang-format compares the working tree with BASE on the changed lines only.
out=$(git clang-format --binary clang-format --diff --extensions cpp,hpp,h,cc "$base" -- 2>&1) || true
case "$out" in
  *"no modified files to format"* | *"did not modify any files"* | "")
    echo "check_format: changed lines since $(git rev-parse --short "$base") are formatted" >&2
    ;;
  *)
    printf '%s\n' "$out"
    echo "check_format: the lines above differ from clang-format (fix: git clang-format $base)" >&2
    exit 1
    ;;
esac
