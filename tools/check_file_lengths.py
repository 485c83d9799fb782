#!/usr/bin/env python3
"""Refuses source files longer than a limit (700 lines by default).

A file past that size has usually grown a second job; splitting it along that seam keeps each file readable
in one sitting. Usage: check_file_lengths.py [--limit N] ROOT [ROOT...]; prints every file over the limit as
`path: N lines, over the limit of L` and exits 1 if there is any.
"""
import argparse
import os
import sys

EXTENSIONS = (".cpp", ".h", ".hpp", ".comp", ".vert", ".frag", ".glsl", ".py", ".js", ".mjs")
SKIP_DIRS = {"node_modules", "cache", "build", ".git"}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--limit", type=int, default=700)
    parser.add_argument("roots", nargs="+")
    args = parser.parse_args()
    over = []
    for root in args.roots:
        for folder, dirs, files in os.walk(root):
            dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS)
            for name in sorted(files):
                if not name.endswith(EXTENSIONS):
                    continue
                path = os.path.join(folder, name)
                with open(path, "rb") as f:
                    lines = sum(1 for _ in f)
                if lines > args.limit:
                    over.append(f"{path}: {lines} lines, over the limit of {args.limit}")
    for line in over:
        print(line)
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
