#!/usr/bin/env bash
# scripts/check_docs_options.sh [LAMBERT]: every long option that `LAMBERT --help` and
# `LAMBERT COMMAND --help` print (for every subcommand `LAMBERT --help` lists) must be
# mentioned, as `--name`, in the manual (docs/*.md); and README.md must stay an entry point of
# at most 300 lines (the manual lives in docs/). Exits 1 listing what is missing.
# LAMBERT defaults to build/bin/lambert. Runs only --help: no scene is loaded.
set -euo pipefail
lambert=${1:-}
[[ -n "$lambert" && "$lambert" != /* ]] && lambert=$PWD/$lambert  # relative to the caller
cd "$(dirname "$0")/.."
lambert=${lambert:-build/bin/lambert}
max_readme_lines=300

if [[ ! -x "$lambert" ]]; then
  echo "check_docs_options: $lambert is not an executable (build first, or pass the binary)" >&2
  exit 2
fi

top_help=$("$lambert" --help)
# The subcommands: the first word of each indented line after "Subcommands:".
mapfile -t commands < <(awk '/^Subcommands:/ { in_list = 1; next }
                              in_list && /^[^ ]/ { in_list = 0 }
                              in_list && NF { print $1 }' <<<"$top_help")
if ((${#commands[@]} == 0)); then
  echo "check_docs_options: no subcommands found in '$lambert --help'" >&2
  exit 2
fi

# Every long option in the help texts (option columns and descriptions alike).
options=$(
  {
    printf '%s\n' "$top_help"
    for command in "${commands[@]}"; do
      "$lambert" "$command" --help
    done
  } | grep -oE -- '--[A-Za-z0-9][A-Za-z0-9-]*' | sort -u
)

shopt -s nullglob
docs=(docs/*.md)
if ((${#docs[@]} == 0)); then
  echo "check_docs_options: no docs/*.md" >&2
  exit 1
fi

missing=()
while IFS= read -r option; do
  # --name as a whole word: not a prefix of a longer option (--ff of --ff-tol).
  if ! grep -qE -- "${option}([^A-Za-z0-9-]|$)" "${docs[@]}"; then
    missing+=("$option")
  fi
done <<<"$options"

status=0
count=$(wc -l <<<"$options")
if ((${#missing[@]} > 0)); then
  echo "check_docs_options: ${#missing[@]} of $count options of $lambert are in no docs/*.md:" >&2
  printf '  %s\n' "${missing[@]}" >&2
  status=1
else
  echo "check_docs_options: all $count options of ${#commands[@]} commands are in docs/*.md"
fi

readme_lines=$(wc -l <README.md)
if ((readme_lines > max_readme_lines)); then
  echo "check_docs_options: README.md has $readme_lines lines, more than $max_readme_lines" \
    "(the manual belongs in docs/)" >&2
  status=1
fi
exit "$status"
