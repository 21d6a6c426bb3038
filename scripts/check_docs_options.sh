#!/usr/bin/env bash
# scripts/check_docs_options.sh [--write] [LAMBERT]: every long option that `LAMBERT --help`
# and `LAMBERT COMMAND --help` print (for every subcommand `LAMBERT --help` lists) must be
# mentioned, as `--name`, in the manual (docs/*.md); the option reference in docs/options.md
# must be what `LAMBERT options --markdown` prints now (--write rewrites it); and README.md
# must stay an entry point of at most 300 lines (the manual lives in docs/). Exits 1 listing
# what is missing. LAMBERT defaults to build/bin/lambert. Runs only --help and `options`.
set -euo pipefail
write=false
if [[ "${1:-}" == --write ]]; then
  write=true
  shift
fi
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

# The generated reference: the lines between the two markers of docs/options.md.
begin='<!-- options reference: `lambert options --markdown` (scripts/check_docs_options.sh --write) -->'
end='<!-- end of options reference -->'
reference=docs/options.md
if ! grep -qxF -- "$begin" "$reference" || ! grep -qxF -- "$end" "$reference"; then
  echo "check_docs_options: $reference lacks the reference markers" >&2
  status=1
else
  current=$(awk -v b="$begin" -v e="$end" '$0 == b { inside = 1; next } $0 == e { inside = 0 }
                                           inside' "$reference")
  generated=$("$lambert" options --markdown)
  if [[ "$current" != "$generated" ]]; then
    if $write; then
      tmp=$(mktemp)
      # (the text through the environment: awk -v would read its backslashes as escapes)
      generated="$generated" awk -v b="$begin" -v e="$end" '
        $0 == b { print; print ENVIRON["generated"]; skipping = 1; next }
        $0 == e { skipping = 0 }
        !skipping' "$reference" >"$tmp"
      mv "$tmp" "$reference"
      echo "check_docs_options: rewrote the option reference in $reference"
    else
      echo "check_docs_options: the option reference in $reference is not what" \
        "'lambert options --markdown' prints (run scripts/check_docs_options.sh --write):" >&2
      diff <(printf '%s\n' "$current") <(printf '%s\n' "$generated") | head -20 >&2 || true
      status=1
    fi
  fi
fi

readme_lines=$(wc -l <README.md)
if ((readme_lines > max_readme_lines)); then
  echo "check_docs_options: README.md has $readme_lines lines, more than $max_readme_lines" \
    "(the manual belongs in docs/)" >&2
  status=1
fi
exit "$status"
