#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Formats (or with --check, verifies) every C/C++ file the project owns: all of core/, drivers/,
# apps/ and tests/, minus the explicit exclusion list (generated code lives in build trees only).
# One pinned formatter: Debian bookworm's clang-format 14.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
CF="${CLANG_FORMAT:-$(command -v clang-format-14 || command -v clang-format || true)}"
if [ -z "$CF" ]; then echo "format.sh: clang-format not found (run tools/setup.sh)" >&2; exit 2; fi
EXCLUDE_RE='^(build|\.venv)/'
mapfile -t files < <(git ls-files --cached --others --exclude-standard -- \
    'core/*' 'drivers/*' 'apps/*' 'tests/*' | grep -E '\.(c|h|cpp|hpp)$' | grep -Ev "$EXCLUDE_RE" || true)
if [ "${#files[@]}" -eq 0 ]; then echo "format.sh: no files"; exit 0; fi
if [ "${1:-}" = "--check" ]; then
  bad=0
  for f in "${files[@]}"; do
    if ! "$CF" --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then
      echo "needs formatting: $f"; bad=1
    fi
  done
  if [ "$bad" -ne 0 ]; then echo "run tools/format.sh to fix"; exit 1; fi
  echo "format: ${#files[@]} files clean ($("$CF" --version | head -1))"
else
  "$CF" --style=file -i "${files[@]}"
  echo "formatted ${#files[@]} files"
fi
