#!/usr/bin/env python3
"""Link layering: the named targets must not reach the named libraries through any chain of links.

Usage: check_links.py LINK_GRAPH TARGET[,TARGET...] FORBIDDEN[,FORBIDDEN...]

LINK_GRAPH is CMake's link graph (sffd_write_link_graph, the file tools/check_includes.py reads). Every
link counts, $<LINK_ONLY:...> included: a static library's private dependencies still end up in whatever
links it. Prints the chain for each target that reaches a forbidden library and exits 1 if any does.
Used to keep the file formats' codecs (zstd, libwebp, tinygltf) out of the residency, picking and render
libraries, which need none of them.
"""
import re
import sys


def read_links(path):
    links = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.rstrip("\n").split("\t")
            entries = [x for x in (fields[5] + ";" + fields[6]).split(";") if x]
            links[fields[0]] = [re.sub(r"^\$<LINK_ONLY:(.*)>$", r"\1", x) for x in entries]
    return links


def chain(links, start, forbidden):
    """The first link chain from start to a forbidden library (breadth first), or None."""
    parent = {start: None}
    queue = [start]
    while queue:
        t = queue.pop(0)
        if t in forbidden and t != start:
            path = [t]
            while parent[path[-1]] is not None:
                path.append(parent[path[-1]])
            return list(reversed(path))
        for d in links.get(t, []):
            if d not in parent:
                parent[d] = t
                queue.append(d)
    return None


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: check_links.py LINK_GRAPH TARGET[,TARGET...] FORBIDDEN[,FORBIDDEN...]")
    links = read_links(sys.argv[1])
    targets, forbidden = sys.argv[2].split(","), set(sys.argv[3].split(","))
    bad = 0
    for t in targets:
        if t not in links:
            print(f"check_links: no target {t} in the link graph")
            bad += 1
            continue
        c = chain(links, t, forbidden)
        if c:
            print(f"check_links: {t} links {c[-1]}: " + " -> ".join(c))
            bad += 1
    if bad:
        return 1
    print(f"check_links: {', '.join(targets)} reach none of {', '.join(sorted(forbidden))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
