#!/usr/bin/env python3
"""The scene format's descriptions agree with the code, and every input file with them.

1. docs/scene.schema.json and docs/element-test.schema.json are exactly what `talus schema` and
   `talus schema --element-test` print; the key table of docs/scene-reference.md (between the
   "talus schema --markdown" markers) is exactly what `talus schema --markdown` prints.
2. Every scene under inputs/ is valid against the scene schema, every spec under
   inputs/element_tests/ against the element-test schema (python3-jsonschema, Draft 7).
3. The schemas are not vacuous: a misspelt key, a value out of range and a missing required key
   are each refused.
Run by ctest as SceneSchema.DocsMatchTheCode; to refresh the docs after changing a field table:
  talus schema > docs/scene.schema.json; talus schema --element-test > docs/element-test.schema.json
and paste `talus schema --markdown` between the markers (or run this script with --write).
"""
import argparse
import copy
import json
import os
import pathlib
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_checks import require_talus  # noqa: E402

import jsonschema

BEGIN = "<!-- begin: talus schema --markdown -->\n"
END = "<!-- end: talus schema --markdown -->"


def talus(binary, *args):
    return subprocess.run([binary, "schema", *args], check=True, capture_output=True, text=True).stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--talus", required=True, help="the talus program")
    parser.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent)
    parser.add_argument("--write", action="store_true", help="rewrite the docs from the code instead of checking")
    args = parser.parse_args()
    require_talus(args.talus)  # was a subprocess traceback
    docs = args.root / "docs"
    failures = []

    generated = {
        docs / "scene.schema.json": talus(args.talus),
        docs / "element-test.schema.json": talus(args.talus, "--element-test"),
    }
    reference = docs / "scene-reference.md"
    text = reference.read_text(encoding="utf-8")
    begin, end = text.find(BEGIN), text.find(END)
    if begin < 0 or end < begin:
        failures.append(f"{reference}: the markers {BEGIN.strip()} ... {END} are missing")
    else:
        generated[reference] = text[: begin + len(BEGIN)] + talus(args.talus, "--markdown") + text[end:]

    for path, content in generated.items():
        if args.write:
            path.write_text(content, encoding="utf-8")
        elif not path.exists() or path.read_text(encoding="utf-8") != content:
            failures.append(f"{path.relative_to(args.root)} differs from what `talus schema` prints "
                            f"(rerun tools/check_scene_schema.py --write --talus ...)")

    scene_schema = json.loads(generated[docs / "scene.schema.json"])
    spec_schema = json.loads(generated[docs / "element-test.schema.json"])
    jsonschema.Draft7Validator.check_schema(scene_schema)
    jsonschema.Draft7Validator.check_schema(spec_schema)
    scene_validator = jsonschema.Draft7Validator(scene_schema)
    spec_validator = jsonschema.Draft7Validator(spec_schema)

    inputs = sorted((args.root / "inputs").rglob("*.json"))
    counted = {"scene": 0, "element test": 0}
    for path in inputs:
        is_spec = "element_tests" in path.parts
        validator = spec_validator if is_spec else scene_validator
        counted["element test" if is_spec else "scene"] += 1
        for error in validator.iter_errors(json.loads(path.read_text(encoding="utf-8"))):
            where = "/".join(str(p) for p in error.absolute_path) or "(top level)"
            failures.append(f"{path.relative_to(args.root)}: {where}: {error.message}")
    if counted["scene"] == 0 or counted["element test"] == 0:
        failures.append(f"too few inputs found: {counted}")

    # The schema refuses what the reader refuses (one case of each kind).
    scene = json.loads((args.root / "inputs" / "elastic_block_slide.json").read_text(encoding="utf-8"))
    bad = []
    misspelt = copy.deepcopy(scene)
    misspelt["time"]["courrant"] = 0.3
    bad.append(("misspelt key time.courrant", misspelt))
    out_of_range = copy.deepcopy(scene)
    out_of_range["time"]["courant"] = 1.0
    bad.append(("time.courant = 1", out_of_range))
    missing = copy.deepcopy(scene)
    del missing["grid"]["cell_size"]
    bad.append(("no grid.cell_size", missing))
    wrong_model_key = copy.deepcopy(scene)
    first_material = next(iter(wrong_model_key["materials"].values()))
    first_material["model"] = "linear_elastic"
    first_material["friction_angle"] = 30
    bad.append(("friction_angle on a linear_elastic material", wrong_model_key))
    for what, document in bad:
        if scene_validator.is_valid(document):
            failures.append(f"the scene schema accepts a scene with {what}")

    for line in failures:
        print(line)
    if failures:
        return 1
    print(f"schemas and docs match the code; {counted['scene']} scenes and {counted['element test']} "
          f"element-test specs are valid; {len(bad)} bad scenes refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
