#!/usr/bin/env python3
"""gen_vectors.py - writes the library manifest conformance vectors (spec/library.md section 9).

    python3 gen_vectors.py [FOLDER]      (default: the folder of this script)

valid/NAME.json with valid/NAME.expected.json (the entries vff-library reads: mesh, output, vff-bake
arguments, shardMaps, split), the meshes they name (tiny OBJ files written here), and
invalid/ID/NAME.json with invalid/ID/NAME.expected.json (the rule's ID, name, exit code and the JSON
path or LINE:COLUMN its message names). Deterministic: the same bytes on every run.
"""
import json
import os
import sys

TETRA = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
WEDGE = "v 0 0 0\nv 2 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
MESHES = {"valid/tetra.obj": TETRA, "valid/parts/wedge.obj": WEDGE}

# Rules (spec/library.md section 8): ID -> (name, exit code).
RULES = {
    13001: ("manifest-json", 3), 13002: ("manifest-object", 3), 13003: ("library-version-type", 3),
    13004: ("library-version", 5), 13005: ("unknown-member", 3), 13006: ("missing-member", 3),
    13007: ("member-type", 3), 13008: ("unknown-option", 3), 13009: ("option-type", 3),
    13010: ("mesh-path", 3), 13011: ("split-value", 3), 13012: ("output-path", 3),
    13013: ("split-output", 3), 13014: ("duplicate-output", 3), 13015: ("bake-option", 1),
}


def entry(mesh, output, args=(), shard=0, split=""):
    return {"mesh": mesh, "output": output, "args": list(args), "shardMaps": shard, "split": split}


# name: (manifest, expected entries)
VALID = {
    "minimal": ({"vffLibrary": 1, "entries": [{"mesh": "tetra.obj"}]}, [entry("tetra.obj", "tetra.vff")]),
    "empty-entries": ({"vffLibrary": 1, "entries": []}, []),
    "defaults-under-options": (
        {"vffLibrary": 1, "defaults": {"count": 2, "map-size": 4, "normals": True},
         "entries": [{"mesh": "tetra.obj", "options": {"map-size": 8, "normals": False}},
                     {"mesh": "parts/wedge.obj"}]},
        [entry("tetra.obj", "tetra.vff", ["--count", "2", "--map-size", "8"]),
         entry("parts/wedge.obj", "parts/wedge.vff", ["--count", "2", "--map-size", "4", "--normals"])]),
    "option-spellings": (
        {"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "options": {
            "center": [0.25, 0.5, 1e-3], "radius": 2, "map-size": "8", "count": 2.0, "codec": "zstd",
            "zstd-level": 3, "allow-clipped-sphere": True}}]},
        [entry("tetra.obj", "tetra.vff", ["--allow-clipped-sphere", "--center", "0.25", "0.5", "0.001", "--codec", "zstd",
                                          "--count", "2", "--map-size", "8", "--radius", "2", "--zstd-level", "3"])]),
    "output-pattern": (
        {"vffLibrary": 1, "output": "fields/{dir}{stem}-{name}.vff",
         "entries": [{"mesh": "parts/wedge.obj"}, {"mesh": "./tetra.obj"}]},
        [entry("parts/wedge.obj", "fields/parts/wedge-wedge.obj.vff"), entry("./tetra.obj", "fields/tetra-tetra.obj.vff")]),
    "output-dots-in-a-name": (
        {"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "output": "x..y.vff"},
                                      {"mesh": "tetra.obj", "output": "a/.b/..c.vff"}]},
        [entry("tetra.obj", "x..y.vff"), entry("tetra.obj", "a/.b/..c.vff")]),
    "shard-maps": (
        {"vffLibrary": 1, "shardMaps": 10, "entries": [{"mesh": "tetra.obj"},
                                                       {"mesh": "parts/wedge.obj", "shardMaps": 0}]},
        [entry("tetra.obj", "tetra.vff", shard=10), entry("parts/wedge.obj", "parts/wedge.vff")]),
}

# name: (manifest as text, expected entries): the JSON text rules of section 1 that valid text meets.
VALID_TEXT = {
    "bom-and-whitespace": ('\ufeff {"vffLibrary": 1,\r\n\t"entries": [{"mesh": "te\\u0074ra.obj", "output": "\u00e9t\u00e9.vff"}]}\r\n\t ',
                           [entry("tetra.obj", "\u00e9t\u00e9.vff")]),
    "large-numbers": ('{"vffLibrary": 1, "shardMaps": 18446744073709551615, "entries": [{"mesh": "tetra.obj", '
                      '"options": {"radius": 1e30, "center": [1e-400, -0.0, 5e-324]}}]}\n',
                      [entry("tetra.obj", "tetra.vff", ["--center", "0", "-0", "4.94065646e-324", "--radius", "1e+30"],
                             shard=18446744073709551615)]),
}

# (ID, name): (manifest as text, the path or LINE:COLUMN its message names)
INVALID = {
    (13001, "syntax-error"): ('{"vffLibrary": 1,\n "entries": [}\n', "2:14"),
    (13001, "repeated-member"): ('{"vffLibrary": 1, "entries": [], "entries": []}\n', "1:34"),
    (13001, "trailing-nul"): ('{"vffLibrary": 1, "entries": []}\x00', "1:33"),
    (13001, "number-out-of-range"): ('{"vffLibrary": 1, "shardMaps": 1e400, "entries": []}\n', "1:32"),
    (13001, "too-deep"): ('{"vffLibrary": 1, "entries": [], "defaults": {"grid": ' + "[" * 63 + "]" * 63 + "}}\n", "1:117"),
    (13002, "not-an-object"): ("[1]\n", ""),
    (13002, "no-version"): ('{"entries": []}\n', ""),
    (13003, "version-string"): ('{"vffLibrary": "1", "entries": []}\n', "vffLibrary"),
    (13003, "version-fraction"): ('{"vffLibrary": 1.0, "entries": []}\n', "vffLibrary"),
    (13004, "version-2"): ('{"vffLibrary": 2, "entries": [], "future": true}\n', "vffLibrary"),
    (13005, "unknown-top-member"): ('{"vffLibrary": 1, "entries": [], "threads": 4}\n', "threads"),
    (13005, "unknown-entry-member"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "name": "t"}]}\n', "entries[0].name"),
    (13006, "no-entries"): ('{"vffLibrary": 1}\n', "entries"),
    (13006, "no-mesh"): ('{"vffLibrary": 1, "entries": [{"output": "a.vff"}]}\n', "entries[0].mesh"),
    (13007, "wrong-type-output"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "output": 5}]}\n', "entries[0].output"),
    (13007, "wrong-type-pattern"): ('{"vffLibrary": 1, "output": 7, "entries": []}\n', "output"),
    (13007, "shard-maps-string"): ('{"vffLibrary": 1, "shardMaps": "5", "entries": []}\n', "shardMaps"),
    (13007, "shard-maps-negative"): ('{"vffLibrary": 1, "shardMaps": -1, "entries": []}\n', "shardMaps"),
    (13007, "shard-maps-fraction"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "shardMaps": 2.5}]}\n', "entries[0].shardMaps"),
    (13007, "entries-object"): ('{"vffLibrary": 1, "entries": {"mesh": "tetra.obj"}}\n', "entries"),
    (13007, "entry-string"): ('{"vffLibrary": 1, "entries": ["tetra.obj"]}\n', "entries[0]"),
    (13007, "mesh-number"): ('{"vffLibrary": 1, "entries": [{"mesh": 1}]}\n', "entries[0].mesh"),
    (13008, "unknown-default-option"): ('{"vffLibrary": 1, "defaults": {"threads": 4}, "entries": []}\n', "defaults.threads"),
    (13008, "split-as-option"): ('{"vffLibrary": 1, "entries": [{"mesh": "s.gltf", "options": {"split": "mesh"}}]}\n', "entries[0].options.split"),
    (13009, "flag-string"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "options": {"normals": "yes"}}]}\n', "entries[0].options.normals"),
    (13009, "center-two-numbers"): ('{"vffLibrary": 1, "defaults": {"center": [0, 0]}, "entries": []}\n', "defaults.center"),
    (13009, "value-array"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "options": {"map-size": [8]}}]}\n', 'entries[0].options["map-size"]'),
    (13008, "names-before-types"): ('{"vffLibrary": 1, "defaults": {"count": [], "zz": 1}, "entries": []}\n', "defaults.zz"),
    (13010, "empty-mesh"): ('{"vffLibrary": 1, "entries": [{"mesh": "", "output": "a.vff"}]}\n', "entries[0].mesh"),
    (13011, "split-triangles"): ('{"vffLibrary": 1, "entries": [{"mesh": "s.gltf", "split": "triangles"}]}\n', "entries[0].split"),
    (13012, "output-parent"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "output": "a/../../b.vff"}]}\n', "entries[0].output"),
    (13012, "output-absolute"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "output": "/tmp/a.vff"}]}\n', "entries[0].output"),
    (13012, "output-empty-segment"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "output": "a//b.vff"}]}\n', "entries[0].output"),
    (13012, "pattern-mesh-outside"): ('{"vffLibrary": 1, "entries": [{"mesh": "../tetra.obj"}]}\n', "entries[0]"),
    (13013, "split-output-vff"): ('{"vffLibrary": 1, "entries": [{"mesh": "s.gltf", "split": "mesh", "output": "s.vff"}]}\n', "entries[0].output"),
    (13014, "two-entries-one-output"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj"}, {"mesh": "a.obj", "output": "tetra.vff"}]}\n', "entries[1].output"),
    (13014, "same-mesh-twice"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj"}, {"mesh": "./tetra.obj"}]}\n', "entries[1]"),
    (13015, "map-size-zero"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "options": {"map-size": 0}}]}\n', "entries[0].options"),
    (13015, "split-of-obj"): ('{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "split": "mesh"}]}\n', "entries[0].options"),
    # Order (section 8): the version before unknown members, the first entry's problem before the second's.
    (13004, "version-before-unknown-member"): ('{"vffLibrary": 3, "shards": 1, "entries": 5}\n', "vffLibrary"),
    (13007, "first-entry-first"): ('{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "output": 1}, {"mash": "b.obj"}]}\n', "entries[0].output"),
}


def write(root, rel, data):
    path = os.path.join(root, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode("utf-8") if isinstance(data, str) else data)


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    for rel, text in MESHES.items():
        write(root, rel, text)
    for name, (manifest, entries) in VALID.items():
        write(root, f"valid/{name}.json", json.dumps(manifest, indent=1) + "\n")
        write(root, f"valid/{name}.expected.json", json.dumps({"exitCode": 0, "entries": entries}, indent=1) + "\n")
    for name, (text, entries) in VALID_TEXT.items():
        write(root, f"valid/{name}.json", text)
        write(root, f"valid/{name}.expected.json", json.dumps({"exitCode": 0, "entries": entries}, indent=1) + "\n")
    for (rid, name), (text, where) in INVALID.items():
        rule, code = RULES[rid]
        # The text the rule prints: "name (ID)", then the place (a JSON path after ": ", or LINE:COLUMN).
        write(root, f"invalid/{rid}/{name}.json", text)
        write(root, f"invalid/{rid}/{name}.expected.json",
              json.dumps({"id": rid, "name": rule, "exitCode": code, "where": where}, indent=1) + "\n")


if __name__ == "__main__":
    main()
