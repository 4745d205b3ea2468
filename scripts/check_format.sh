#!/usr/bin/env bash
# Checks that every C++ source the repository tracks is formatted as .clang-format says
# (clang-format 14, Debian 12's). Names each file that is not, with its first differences,
# and exits 1. To format the lines a change touches: git clang-format-14 --binary clang-format-14.
set -euo pipefail
cd "$(dirname "$0")/.."
formatter=${CLANG_FORMAT:-clang-format-14}
if ! command -v "$formatter" > /dev/null; then
  echo "check_format: $formatter is missing (scripts/install-deps.sh installs it)" >&2
  exit 2
fi
mapfile -t files < <(git ls-files '*.cpp' '*.h')
# --dry-run reports each misformatted place as "FILE:LINE:COLUMN: error: code should be...".
mapfile -t unformatted < <(printf '%s\0' "${files[@]}" |
  xargs -0 "$formatter" --dry-run --Werror 2>&1 |
  sed -n 's/^\(.*\):[0-9]*:[0-9]*: error: code should be clang-formatted.*/\1/p' | sort -u)
if ((${#unformatted[@]} > 0)); then
  echo "check_format: ${#unformatted[@]} of ${#files[@]} files are not formatted:" >&2
  for file in "${unformatted[@]}"; do
    echo "  $file" >&2
    "$formatter" "$file" | diff -u "$file" - | sed -n '3,12p' | sed 's/^/    /' >&2 || true
  done
  echo "check_format: run $formatter -i on them (or git clang-format-14 on a change)" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files formatted as .clang-format says"
