#!/usr/bin/env python3
"""The layer rule (docs/architecture.md "Layers"): a file of one layer may include headers of its
own layer and of the layers below it, never of a layer above it. The order comes from CMakeLists.txt
(TALUS_LAYERS, lowest first), which passes it here; ctest runs this as Layers.NoUpwardIncludes.

A file's layer is its folder: src/<layer>/... or include/talus/<layer>/...; an include names the
layer of the header it pulls in: "talus/<layer>/..." or <talus/<layer>/...>, or a private header of
src/, "<layer>/..." (when <layer> is one of the layers; "hwy/...", "fmt/..." are not). Exit 1 with
one line per offending include.
"""
import argparse
import pathlib
import re
import sys

# "talus/<layer>/..." and <talus/<layer>/...>: the name must be a layer
INCLUDE = re.compile(r'^\s*#\s*include\s*(?:"talus/([a-z_]+)/[^"]+"|<talus/([a-z_]+)/[^>]+>)', re.MULTILINE)
# "<name>/...": a private header of src/<name>/ when <name> is a layer (else another library's)
PRIVATE_INCLUDE = re.compile(r'^\s*#\s*include\s*"([a-z_]+)/[^"]+"', re.MULTILINE)


def layer_of(path: pathlib.Path, root: pathlib.Path):
    parts = path.relative_to(root).parts
    if parts[0] == "src" and len(parts) > 2:
        return parts[1]
    if parts[:2] == ("include", "talus") and len(parts) > 3:
        return parts[2]
    return None


def violations(root: pathlib.Path, layers):
    rank = {name: i for i, name in enumerate(layers)}
    found = []
    files = [p for d in ("src", "include/talus") for p in sorted((root / d).rglob("*"))
             if p.suffix in (".hpp", ".cpp", ".in", ".h")]
    for path in files:
        layer = layer_of(path, root)
        if layer is None:
            continue
        if layer not in rank:
            found.append(f"{path.relative_to(root)}: folder '{layer}' is not a layer (add it to TALUS_LAYERS)")
            continue
        text = path.read_text(encoding="utf-8")
        matches = [(m.group(1) or m.group(2), m.start()) for m in INCLUDE.finditer(text)]
        matches += [(m.group(1), m.start()) for m in PRIVATE_INCLUDE.finditer(text)
                    if m.group(1) in rank and m.group(1) != "talus"]
        for target, start in sorted(matches, key=lambda t: t[1]):
            line = text.count("\n", 0, start) + 1
            if target not in rank:
                found.append(f"{path.relative_to(root)}:{line}: includes talus/{target}/, which is not a layer")
            elif rank[target] > rank[layer]:
                found.append(f"{path.relative_to(root)}:{line}: layer '{layer}' includes talus/{target}/, "
                             f"a layer above it ({' < '.join(layers)})")
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent)
    parser.add_argument("--layers", nargs="+", required=True, help="layer folders, lowest first")
    args = parser.parse_args()
    root = args.root.resolve()
    missing = [str(root / d) for d in ("src", "include/talus") if not (root / d).is_dir()]
    if missing:  # a wrong --root checked no file and said "layers ok"
        print(f"check_layers.py: --root {args.root}: no {' and no '.join(missing)}", file=sys.stderr)
        return 2
    found = violations(root, args.layers)
    for line in found:
        print(line)
    if found:
        return 1
    print(f"layers ok: {' < '.join(args.layers)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
