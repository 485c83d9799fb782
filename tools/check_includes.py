#!/usr/bin/env python3
"""Include boundaries: a target may include only the headers of targets it links.

Usage: check_includes.py LINK_GRAPH SOURCE_ROOT

LINK_GRAPH is written by CMake at configure time (sffd_write_link_graph in cmake/SplatffdTargets.cmake),
one line per project target, tab-separated:
    name  type  source_dir  sources(;)  header_dirs(;)  link_libraries(;)  interface_link_libraries(;)
Every target includes from the repository root, so the compiler cannot stop `picking` from including a
`gaussian` header without linking sffd_gaussian; this check does, from the link graph CMake already has.

Who owns a header: the library with the .cpp of the same name among its sources; a header without one
belongs to the libraries whose folder it is in (the folders of their sources, or header_dirs for
header-only libraries). Headers outside every library folder (tests/, shaders/, tools/bench/) are free.
What a target may include: its own headers and those of every library in its link closure: its direct
link libraries, then their interface link libraries, transitively ($<LINK_ONLY:...> entries are link
order only, their headers are not visible). Layers: a file under runtime/ never includes a header under
systems/ (the runtime, formats included, is below every system), linked or not.
Prints one line per violation and exits 1 if there is any.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def split_list(field):
    return [x for x in field.split(";") if x and not x.endswith("-NOTFOUND")]


def read_graph(path, root):
    targets = {}
    with open(path, encoding="utf-8") as f:
        for lineno, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line or line.startswith("#"):
                continue
            fields = line.split("\t")
            if len(fields) != 7:
                sys.exit(f"{path}:{lineno}: expected 7 tab-separated fields, found {len(fields)}")
            name, kind, source_dir, sources, header_dirs, link, interface = fields
            source_dir = os.path.join(root, source_dir)
            srcs = [os.path.relpath(os.path.normpath(os.path.join(source_dir, s)), root) for s in split_list(sources)]
            dirs = {os.path.dirname(s) for s in srcs if s.endswith(".cpp")}
            dirs |= {os.path.relpath(os.path.join(root, d), root) for d in split_list(header_dirs)}
            targets[name] = {
                "library": kind.endswith("_LIBRARY"),
                "sources": srcs,
                "dirs": dirs,
                "link": split_list(link),
                "interface": [x for x in split_list(interface) if not x.startswith("$<LINK_ONLY:")],
            }
    return targets


def closure(targets, name):
    """The targets whose headers `name` sees: itself, its direct links and their interface links."""
    seen = {name}
    stack = list(targets[name]["link"] if name in targets else [])
    while stack:
        t = stack.pop()
        if t in seen:
            continue
        seen.add(t)
        if t in targets:
            stack.extend(targets[t]["interface"])
    return seen


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: check_includes.py LINK_GRAPH SOURCE_ROOT")
    graph_path, root = sys.argv[1], os.path.abspath(sys.argv[2])
    targets = read_graph(graph_path, root)

    # Owners of each header in a library folder.
    stem_owner = {}
    dir_owners = {}
    for name, t in targets.items():
        if not t["library"]:
            continue
        for s in t["sources"]:
            if s.endswith(".cpp"):
                stem_owner[s[:-4] + ".h"] = name
        for d in t["dirs"]:
            dir_owners.setdefault(d, set()).add(name)

    def owners(header):
        if header in stem_owner:
            return {stem_owner[header]}
        return dir_owners.get(os.path.dirname(header), set())

    # Files checked per target: its sources and the headers it owns (a header-only header in a folder
    # shared by several libraries is checked against what any of them sees).
    checked = {}
    for name, t in targets.items():
        for s in t["sources"]:
            checked.setdefault(s, set()).add(name)
    for d, names in dir_owners.items():
        folder = os.path.join(root, d)
        if not os.path.isdir(folder):
            continue
        for entry in sorted(os.listdir(folder)):
            if entry.endswith(".h"):
                h = os.path.join(d, entry)
                checked.setdefault(h, set()).update(owners(h))

    closures = {name: closure(targets, name) for name in targets}
    violations = []
    for path, names in sorted(checked.items()):
        full = os.path.join(root, path)
        try:
            with open(full, encoding="utf-8", errors="replace") as f:
                text = f.read()
        except OSError as e:
            violations.append(f"{path}: cannot read: {e.strerror}")
            continue
        visible = set().union(*(closures[n] for n in names))
        for inc in INCLUDE.findall(text):
            if os.path.exists(os.path.join(root, inc)):
                header = os.path.normpath(inc)
            else:
                header = os.path.relpath(os.path.normpath(os.path.join(os.path.dirname(full), inc)), root)
            if path.startswith("runtime/") and header.startswith("systems/"):
                violations.append(f"{path}: includes {header}: runtime/ is below systems/ and includes none of it")
                continue
            own = owners(header)
            if own and not (own & visible):
                who = " or ".join(sorted(names))
                violations.append(f"{path}: includes {header} (library {' or '.join(sorted(own))}), "
                                  f"which {who} does not link")
    for v in violations:
        print(v)
    if violations:
        print(f"check_includes: {len(violations)} include(s) cross a library boundary without a link or a layer downwards")
        return 1
    print(f"check_includes: {len(checked)} files of {len(targets)} targets include only what they link")
    return 0


if __name__ == "__main__":
    sys.exit(main())
