#!/usr/bin/env python3
"""Scene-description conformance vectors (spec/scene.md): writes valid/ and invalid/ beside itself.

    python3 spec/conformance/scene/generate.py           # (re)writes the vectors
    python3 spec/conformance/scene/generate.py --check   # exit 1 if a committed file differs

Deterministic: the texts are literals below; the expected values are computed here, independently
of libvff, with binary32 rounding done by struct (round to nearest). See README.md.
"""
import json
import math
import pathlib
import struct
import sys

HERE = pathlib.Path(__file__).resolve().parent
FIELDS = HERE.parent / "valid"  # the .vff conformance vectors that valid scenes name
HEAD = '{"asset": {"format": "vff-scene", "version": 1}, '
U8D = "../../valid/u8d-stored.vff"
U16D = "../../valid/u16d-stored-meta-slices.vff"


def f32(x):
    """x rounded to binary32 (nearest), or None where that overflows (spec/scene.md section 1, rule 4)."""
    try:
        return struct.unpack("<f", struct.pack("<f", x))[0]
    except OverflowError:
        return None


def scene(fields, instances, extra=""):
    return HEAD + '"fields": [' + ", ".join(fields) + '], "instances": [' + ", ".join(instances) + "]" + extra + "}\n"


def inst(body):
    return "{" + body + "}"


# ---- Invalid vectors: invalid/ID/NAME.json and what each shows --------------------------------------
ONE_FIELD = ['{"uri": "a.vff"}']
INVALID = {
    11001: {
        "syntax-missing-comma": scene(ONE_FIELD, []).replace('"version": 1}, ', '"version": 1} '),
        "empty-text": "",
        "trailing-nul": scene([], []) + "\0",
        "trailing-value": scene([], []) + "{}\n",
        "two-byte-order-marks": "\ufeff\ufeff" + scene([], []),
        "depth-65-in-extras": scene([], [], ', "extras": ' + "[" * 64 + "]" * 64),
        "number-overflow-in-extras": scene([], [], ', "extras": {"big": 1e400}'),
        "integer-overflow-in-extras": scene([], [], ', "extras": ' + "1" + "0" * 400),
        "repeated-member-top": scene([], []).replace('"instances": []', '"instances": [], "fields": []'),
        "repeated-member-in-extras": scene([], [], ', "extras": {"k": 1, "k": 1}'),
        "invalid-utf8-in-name": scene(['{"uri": "a.vff", "name": "\udcc3("}'], []),
        "lone-surrogate-escape": scene(['{"uri": "a.vff", "name": "\\ud800"}'], []),
        "control-character-in-string": scene(['{"uri": "a.vff", "name": "a\tb"}'], []),
        "not-an-object": "[" + scene([], []).strip() + "]\n",
        "single-quotes": scene([], []).replace('"format"', "'format'"),
        "json-error-before-version": '{"asset": {"format": "vff-scene", "version": 2}, "fields": [,]}\n',
    },
    11002: {
        "format-gltf": scene([], []).replace('"vff-scene"', '"gltf"'),
        "format-not-a-string": scene([], []).replace('"vff-scene"', "1"),
        "version-2": scene([], []).replace('"version": 1', '"version": 2'),
        "version-string": scene([], []).replace('"version": 1', '"version": "1"'),
        "version-1.5": scene([], []).replace('"version": 1', '"version": 1.5'),
        "version-before-fields": '{"asset": {"format": "vff-scene", "version": 2}}\n',
        # An integer is written without a fraction or an exponent (spec/scene.md section 1).
        "version-1.0": scene([], []).replace('"version": 1', '"version": 1.0'),
        "version-exponent": scene([], []).replace('"version": 1', '"version": 1e0'),
        "integers-by-value": scene(['{"uri": "a.vff"}', '{"uri": "b.vff"}'], [inst('"field": 1.0'), inst('"field": 0e5')]
                                   ).replace('"version": 1', '"version": 1.0, "minorVersion": 2e1'),
    },
    11003: {
        "asset-missing": '{"fields": [], "instances": []}\n',
        "asset-not-an-object": '{"asset": "vff-scene", "fields": [], "instances": []}\n',
        "format-missing": '{"asset": {"version": 1}, "fields": [], "instances": []}\n',
        "version-missing": '{"asset": {"format": "vff-scene"}, "fields": [], "instances": []}\n',
        "minor-version-negative": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": -1'),
        "minor-version-string": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": "1"'),
        "minor-version-fraction": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": 0.5'),
        "minor-version-2.0": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": 2.0'),
        "minor-version-exponent": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": 2e1'),
        "minor-version-beyond-64-bits": scene([], []).replace('"version": 1', '"version": 1, "minorVersion": 18446744073709551616'),
        "generator-not-a-string": scene([], []).replace('"version": 1', '"version": 1, "generator": 3'),
        "fields-missing": HEAD + '"instances": []}\n',
        "fields-not-an-array": HEAD + '"fields": {}, "instances": []}\n',
        "instances-missing": HEAD + '"fields": []}\n',
        "field-not-an-object": scene(['"a.vff"'], []),
        "uri-missing": scene(['{"name": "a"}'], []),
        "uri-not-a-string": scene(['{"uri": 5}'], []),
        "field-name-not-a-string": scene(['{"uri": "a.vff", "name": null}'], []),
        "source-not-an-object": scene(['{"uri": "a.vff", "source": "x.glb"}'], []),
        "instance-not-an-object": scene(ONE_FIELD, ["0"]),
        "instance-field-missing": scene(ONE_FIELD, [inst('"name": "x"')]),
        "instance-field-fraction": scene(ONE_FIELD, [inst('"field": 0.5')]),
        "instance-field-0.0": scene(ONE_FIELD, [inst('"field": 0.0')]),
        "instance-field-exponent": scene(ONE_FIELD, [inst('"field": 0e5')]),
        "instance-field-huge-exponent": scene(ONE_FIELD, [inst('"field": 1e30')]),
        "instance-field-beyond-64-bits": scene(ONE_FIELD, [inst('"field": 18446744073709551616')]),
        "instance-field-below-64-bits": scene(ONE_FIELD, [inst('"field": -9223372036854775809')]),
        "minor-version-before-field": scene(['{"uri": "a.vff"}', '{"uri": "b.vff"}'], [inst('"field": 1.0')]
                                            ).replace('"version": 1', '"version": 1, "minorVersion": 2e1'),
        "instance-field-by-value": scene(['{"uri": "a.vff"}', '{"uri": "b.vff"}'], [inst('"field": 1.0'), inst('"field": 0e5')]),
        "instance-field-string": scene(ONE_FIELD, [inst('"field": "0"')]),
        "instance-name-not-a-string": scene(ONE_FIELD, [inst('"field": 0, "name": 1')]),
        "translation-two-numbers": scene(ONE_FIELD, [inst('"field": 0, "translation": [0, 0]')]),
        "translation-string-element": scene(ONE_FIELD, [inst('"field": 0, "translation": [0, "1", 0]')]),
        "translation-not-finite-in-binary32": scene(ONE_FIELD, [inst('"field": 0, "translation": [0, 1e39, 0]')]),
        "translation-halfway-to-2-128": scene(ONE_FIELD, [inst('"field": 0, "translation": [3.4028235677973366e38, 0, 0]')]),
        "rotation-not-unit": scene(ONE_FIELD, [inst('"field": 0, "rotation": [0, 0, 0, 1.0011]')]),
        "rotation-zero": scene(ONE_FIELD, [inst('"field": 0, "rotation": [0, 0, 0, 0]')]),
        "rotation-three-numbers": scene(ONE_FIELD, [inst('"field": 0, "rotation": [0, 0, 1]')]),
        "scale-zero": scene(ONE_FIELD, [inst('"field": 0, "scale": 0')]),
        "scale-negative": scene(ONE_FIELD, [inst('"field": 0, "scale": -2')]),
        "scale-rounds-to-zero-in-binary32": scene(ONE_FIELD, [inst('"field": 0, "scale": 1e-50')]),
        "scale-not-finite-in-binary32": scene(ONE_FIELD, [inst('"field": 0, "scale": 1e39')]),
        "scale-array": scene(ONE_FIELD, [inst('"field": 0, "scale": [1, 1, 1]')]),
        "asset-before-uri": '{"fields": [{"uri": "http://x/a.vff"}], "instances": []}\n',
        "translation-before-rotation": scene(ONE_FIELD, [inst('"field": 0, "rotation": [0, 0, 0, 2], "translation": [1e39, 0, 0]')]),
        "fields-before-instances-member": HEAD + '"instances": [{"field": 7}]}\n',
    },
    11004: {
        "uri-empty": scene(['{"uri": ""}'], []),
        "uri-http-scheme": scene(['{"uri": "http://example.com/a.vff"}'], []),
        "uri-data-scheme": scene(['{"uri": "data:application/octet-stream;base64,AAAA"}'], []),
        "uri-file-scheme": scene(['{"uri": "file:///tmp/a.vff"}'], []),
        "uri-windows-drive": scene(['{"uri": "C:/fields/a.vff"}'], []),
        "uri-windows-drive-backslash": scene(['{"uri": "C:\\\\fields\\\\a.vff"}'], []),
        "uri-backslash": scene(['{"uri": "fields\\\\a.vff"}'], []),
        "uri-network-path": scene(['{"uri": "//server/share/a.vff"}'], []),
        "uri-query": scene(['{"uri": "a.vff?v=2"}'], []),
        "uri-fragment": scene(['{"uri": "a.vff#x"}'], []),
        "uri-percent-one-digit": scene(['{"uri": "a%2.vff"}'], []),
        "uri-percent-not-hex": scene(['{"uri": "a%zz.vff"}'], []),
        "uri-percent-nul": scene(['{"uri": "a%00.vff"}'], []),
        "uri-percent-not-utf8": scene(['{"uri": "a%FF.vff"}'], []),
        "uri-second-field": scene(['{"uri": "a.vff"}', '{"uri": "https://x/b.vff"}'], []),
        "uri-before-instances": scene(['{"uri": "x:a.vff"}'], [inst('"field": 3')]),
    },
    11005: {
        "index-past-the-end": scene(ONE_FIELD, [inst('"field": 1')]),
        "index-negative": scene(ONE_FIELD, [inst('"field": -1')]),
        "index-without-fields": scene([], [inst('"field": 0')]),
        "index-huge": scene(ONE_FIELD, [inst('"field": 18446744073709551615')]),
        "index-most-negative": scene(ONE_FIELD, [inst('"field": -9223372036854775808')]),
        "index-in-second-instance": scene(ONE_FIELD, [inst('"field": 0'), inst('"field": 2')]),
        "index-before-translation": scene(ONE_FIELD, [inst('"field": 1, "translation": [1e39, 0, 0]')]),
    },
}

# ---- Valid vectors: valid/NAME.json ---------------------------------------------------------------
VALID = {
    "empty": scene([], []),
    "two-fields-placed": scene(
        ['{"uri": "%s", "name": "u8d", "source": {"file": "x.glb", "mesh": 0}}' % U8D, '{"uri": "%s"}' % U16D],
        [inst('"field": 0, "name": "left", "translation": [-2, 0, 0.5]'),
         inst('"field": 1, "rotation": [0, 0.70710678, 0, 0.70710678], "scale": 0.5, "translation": [1, 2, 3]'),
         inst('"field": 0, "rotation": [0.5, 0.5, 0.5, 0.5], "scale": 2.25, "translation": [0.1, 0.2, 0.3]')]),
    "byte-order-mark-and-crlf": "\ufeff" + scene(['{"uri": "%s"}' % U8D], [inst('"field": 0')]).replace(", ", ",\r\n\t"),
    "defaults": scene(['{"uri": "%s"}' % U8D], [inst('"field": 0')]),
    "rotation-normalised": scene(['{"uri": "%s"}' % U8D],
                                 [inst('"field": 0, "rotation": [0, 0, 0.6, 0.8009]'),
                                  inst('"field": 0, "rotation": [0, 0, 0, 0.9991]')]),
    "binary32-rounding": scene(['{"uri": "missing.vff"}'],
                               [inst('"field": 0, "translation": [0.1, 16777217, 3.4028235677973362e38], '
                                     '"scale": 1e-45')]),
    "percent-encoded-uri": scene(['{"uri": "../../valid/u8d%2Dstored.vff"}', '{"uri": "sub%20dir/a%25b%C3%A9.vff"}'],
                                 [inst('"field": 0, "scale": 3')]),
    "absolute-and-repeated-uri": scene(['{"uri": "/nonexistent/a.vff"}', '{"uri": "/nonexistent/a.vff"}',
                                        '{"uri": "./b/../c.vff"}'], [inst('"field": 2'), inst('"field": 1')]),
    "unknown-members-and-extras": scene(
        ['{"uri": "a.vff", "future": {"x": [1e308]}, "source": {"k": {"k": 1}}}'],
        [inst('"field": 0, "extras": {"big": 1e308, "small": 1e-400, "deep": ' + "[" * 60 + "]" * 60 + '}, "later": true')],
        ', "extras": {"k": 1}, "later": [1, 2]').replace('"version": 1', '"version": 1, "minorVersion": 7, "generator": "hand", "x": null'),
    "integers-at-the-edges": scene(['{"uri": "a.vff"}', '{"uri": "b.vff"}'], [inst('"field": -0'), inst('"field": 1')]
                                   ).replace('"version": 1', '"version": 1, "minorVersion": 18446744073709551615'),
    "nesting-depth-64": scene([], [], ', "extras": ' + "[" * 63 + "]" * 63),
    "windows-drive-lookalike": scene(['{"uri": "./C:/a.vff"}', '{"uri": "dir/C:a.vff"}'], []),
}

# The world spheres: the object-space spheres of the fields that exist, from their expected JSON.
SPHERES = {}
for name in ("u8d-stored", "u16d-stored-meta-slices"):
    s = json.loads((FIELDS / (name + ".expected.json")).read_text())["field"]["sphere"]
    SPHERES["../../valid/%s.vff" % name] = ([f32(c) for c in s["center"]], f32(s["radius"]))


def decode_uri(uri):
    out, i, b = bytearray(), 0, uri.encode()
    while i < len(b):
        if b[i:i + 1] == b"%":
            out.append(int(b[i + 1:i + 3], 16))
            i += 3
        else:
            out.append(b[i])
            i += 1
    return out.decode()


def rotate(q, v):
    x, y, z, w = q
    m = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return [sum(m[r][c] * v[c] for c in range(3)) for r in range(3)]


def expected(text):
    """What a reader must produce from a valid description (README.md says how to compare)."""
    doc = json.loads(text.lstrip("\ufeff"))
    fields = []
    for f in doc["fields"]:
        path = decode_uri(f["uri"])
        fields.append({"uri": f["uri"], "path": path, "name": f.get("name", ""), "exists": path in SPHERES})
    instances = []
    for i in doc["instances"]:
        t = [f32(v) for v in i.get("translation", [0, 0, 0])]
        q = [f32(v) for v in i.get("rotation", [0, 0, 0, 1])]
        norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
        q = [f32(c / norm) for c in q]
        s = f32(i.get("scale", 1))
        out = {"field": int(i["field"]), "name": i.get("name", ""), "translation": t, "rotation": q, "scale": s}
        path = fields[int(i["field"])]["path"]
        if path in SPHERES:
            c, r = SPHERES[path]
            w = rotate(q, [s * v for v in c])
            out["worldSphere"] = {"center": [t[k] + w[k] for k in range(3)], "radius": s * r}
        instances.append(out)
    return {"generator": doc["asset"].get("generator", ""), "fields": fields, "instances": instances}


def outputs():
    files = {}
    for code, cases in INVALID.items():
        for name, text in cases.items():
            files["invalid/%d/%s.json" % (code, name)] = text.encode("utf-8", "surrogateescape")
    for name, text in VALID.items():
        files["valid/%s.json" % name] = text.encode("utf-8")
        files["valid/%s.expected.json" % name] = (json.dumps(expected(text), indent=2) + "\n").encode()
    return files


def main():
    check = "--check" in sys.argv[1:]
    files, bad = outputs(), []
    present = {str(p.relative_to(HERE)) for p in HERE.glob("*alid/**/*.json")}
    for rel, data in sorted(files.items()):
        path = HERE / rel
        if check:
            if not path.exists() or path.read_bytes() != data:
                bad.append(rel + (" differs" if path.exists() else " is missing"))
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
    for rel in sorted(present - set(files)):
        if check:
            bad.append(rel + " is no longer generated")
        else:
            (HERE / rel).unlink()
    for b in bad:
        print("scene vectors: " + b, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
