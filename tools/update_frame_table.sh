#!/usr/bin/env bash
# Rewrites the frame table in README.md (between the frame-table markers) from the schedule's declared
# access: `splatffd schedule --markdown`. The test engine_tests (EngineSchedule.ReadmeFrameTableIsTheGeneratedOne)
# fails until the README matches. Usage: tools/update_frame_table.sh [build-dir] (default build/release).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-build/release}"
table="$("$build/tools/splatffd" schedule --markdown)"
TABLE="$table" python3 - "$root/README.md" <<'PY'
import os, sys
path = sys.argv[1]
text = open(path, encoding="utf-8").read()
begin, end = "<!-- frame-table:begin", "<!-- frame-table:end -->"
b, e = text.find(begin), text.find(end)
if b < 0 or e < b:
    sys.exit(f"{path}: no frame-table markers")
body = text.index("\n", b) + 1
new = text[:body] + os.environ["TABLE"] + "\n" + text[e:]
tmp = path + ".tmp"
open(tmp, "w", encoding="utf-8").write(new)
os.replace(tmp, path)
PY
echo "README.md: frame table regenerated from $build/tools/splatffd"
