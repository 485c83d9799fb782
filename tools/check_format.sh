#!/usr/bin/env bash
# tools/check_format.sh [FILE...]: checks that tracked C++ files (.cpp, .h; shaders/ excluded: its
# headers are shared with GLSL, which clang-format does not parse) match .clang-format, without changing
# them. Prints each file that differs and the count; exits 1 if any does, 2 if clang-format is missing.
# To fix: clang-format -i FILE (tools/test.sh runs this check and counts it as a failure).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! command -v clang-format >/dev/null 2>&1; then
  echo "check_format: clang-format not found (tools/bootstrap.sh installs it)" >&2
  exit 2
fi

if (($# > 0)); then
  files=("$@")
else
  mapfile -t files < <(git ls-files -- '*.cpp' '*.h' ':!:shaders/*')
fi

# One clang-format process for all files (each violation is a "FILE:LINE:COL: warning:" line).
status=0
report=$(clang-format --dry-run --Werror --style=file "${files[@]}" 2>&1) || status=$?
mapfile -t differ < <(sed -nE 's/^(.+):[0-9]+:[0-9]+: (warning|error): .*/\1/p' <<<"$report" | sort -u)
for f in "${differ[@]}"; do echo "check_format: $f is not formatted (clang-format -i $f)"; done
bad=${#differ[@]}
if ((status != 0 && bad == 0)); then
  echo "check_format: clang-format failed: $report" >&2
  exit 1
fi
if ((bad > 0)); then
  echo "check_format: $bad of ${#files[@]} files differ from .clang-format ($(clang-format --version))"
  exit 1
fi
echo "check_format: ${#files[@]} files match .clang-format"
