"""vff.read_gltf_fields: the fields a glTF asset's meshes carry (VFF_visibility_field)."""
import json
import os
import pathlib
import struct
import subprocess

import numpy as np
import pytest

import vff
from conftest import rays_around


def tool(env):
    exe = os.environ.get(env)
    if not exe:
        pytest.skip("SKIP: %s is not set (run through ctest, with the baker and the samples built)" % env)
    return exe


@pytest.fixture
def asset(tmp_path):
    """The sample scene baked into x.glb (fields on meshes 0 "box" and 1 "knot"; mesh 2 "bowl" is
    not in the default scene) and split per mesh (split/x.mesh0.vff: mesh 0's field, the same bytes)."""
    subprocess.run([tool("VFF_MESHGEN"), "--gltf-scene", str(tmp_path / "s.gltf")], check=True, capture_output=True)
    options = ["-n", "2", "-m", "8"]
    bake = tool("VFF_BAKE")
    subprocess.run([bake, str(tmp_path / "s.gltf"), "-o", str(tmp_path / "x.glb"), *options], check=True,
                   capture_output=True)
    (tmp_path / "split").mkdir()
    subprocess.run([bake, str(tmp_path / "s.gltf"), "--split", "mesh", "-o", str(tmp_path / "split" / "x.vffscene.json"),
                    *options], check=True, capture_output=True)
    return tmp_path


def glb_edit(src, dst, edit):
    """dst: the GLB src with its JSON document j and binary chunk b (a bytearray) changed by edit(j, b)."""
    data = pathlib.Path(src).read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    j = json.loads(data[20:20 + n])
    m = struct.unpack_from("<I", data, 20 + n)[0]
    b = bytearray(data[28 + n:28 + n + m])
    edit(j, b)
    t = json.dumps(j).encode()
    t += b" " * (-len(t) % 4)
    rest = struct.pack("<I4s", len(b), b"BIN\0") + b
    pathlib.Path(dst).write_bytes(struct.pack("<4sII", b"glTF", 2, 20 + len(t) + len(rest)) +
                                  struct.pack("<I4s", len(t), b"JSON") + t + rest)
    return str(dst)


def move(j, b, mesh, f):
    """Mesh `mesh`'s positions p (of its first primitive) replaced by f(k, p), k the vertex index."""
    a = j["accessors"][j["meshes"][mesh]["primitives"][0]["attributes"]["POSITION"]]
    v = j["bufferViews"][a["bufferView"]]
    stride, at = v.get("byteStride", 12), v.get("byteOffset", 0) + a.get("byteOffset", 0)
    ps = []
    for k in range(a["count"]):
        struct.pack_into("<3f", b, at + k * stride, *f(k, struct.unpack_from("<3f", b, at + k * stride)))
        ps.append(struct.unpack_from("<3f", b, at + k * stride))
    a["min"] = [min(p[c] for p in ps) for c in range(3)]
    a["max"] = [max(p[c] for p in ps) for c in range(3)]


def nudge_box(j, b):
    """The box's first vertex moved inward by far less than one distance step: same bounds, another hash."""
    move(j, b, 0, lambda k, p: [c - 1e-4 * (1 if c > 0 else -1) for c in p] if k == 0 else p)


def grow_box(j, b):
    """The box twice as large: its bounds move by half its size."""
    move(j, b, 0, lambda k, p: [2 * c for c in p])


def ext(j, mesh):
    return j["meshes"][mesh]["extensions"]["VFF_visibility_field"]


def test_read_lists_the_fields(asset):
    r = vff.read_gltf_fields(str(asset / "x.glb"))
    assert isinstance(r, vff.GltfFields)
    assert r.mesh_count == 3 and not r.has_error
    assert [f.mesh for f in r.fields] == [0, 1] and [f.name for f in r.fields] == ["box", "knot"]
    split0 = (asset / "split" / "x.mesh0.vff").read_bytes()
    box, knot = r.fields
    assert box.path == "/meshes/0/extensions/VFF_visibility_field"
    assert isinstance(box.buffer_view, int) and box.uri is None
    assert box.bytes == split0
    meta = vff.open(str(asset / "split" / "x.mesh0.vff")).metadata
    assert box.geometry_hash == meta["vff.source"]["geometryHash"] == box.mesh_geometry_hash
    assert box.match == "exact" and box.valid and box.usable
    assert box.bounds_difference == 0 and box.tolerance > 0
    assert all(a <= b for a, b in zip(box.min, box.max))
    assert [(n["node"], n["name"], n["answered"], n["reason"]) for n in box.nodes] == [
        (0, "boxA", True, ""), (1, "boxB", True, "")]
    # The stretched knot's node is not answered; the mesh's field is still valid and usable.
    assert [(n["node"], n["answered"]) for n in knot.nodes] == [(3, False)] and knot.nodes[0]["reason"]
    assert knot.usable and len(knot.bytes) > 0
    assert [(p["rule"], p["name"], p["severity"]) for p in r.problems] == [(14104, "gltf-node-no-field", "note")]
    assert set(r.problems[0]) == {"rule", "name", "severity", "path", "message"}


def test_open_answers_as_the_split_file(asset):
    box = vff.read_gltf_fields(str(asset / "x.glb")).fields[0]
    f = box.open()
    assert isinstance(f, vff.File) and f.path == "" and f.map_count == 26
    ref = vff.open(str(asset / "split" / "x.mesh0.vff"))
    o, d = rays_around(ref.center, ref.radius, 3000, seed=4)
    a, b = vff.FieldQuery(f).intersect(o, d), vff.FieldQuery(ref).intersect(o, d)
    assert a.hit.sum() > 100
    np.testing.assert_array_equal(a.hit, b.hit)
    np.testing.assert_array_equal(a.t, b.t)


def test_a_mismatch_is_not_opened(asset):
    r = vff.read_gltf_fields(glb_edit(asset / "x.glb", asset / "far.glb", grow_box))
    box = r.fields[0]
    assert box.match == "mismatch" and box.valid and not box.usable and not r.has_error
    assert box.geometry_hash != box.mesh_geometry_hash
    assert abs(box.bounds_difference - 0.5) < 1e-6 and 0 < box.tolerance < 0.5
    assert [p["rule"] for p in r.problems if p["severity"] == "warning"] == [14103]
    with pytest.raises(vff.GltfError) as e:
        box.open()
    assert e.value.code == 14103 and e.value.name == "gltf-geometry-mismatch"
    assert e.value.path.startswith("/meshes/0") and isinstance(e.value, vff.Error)
    # Within one distance step of the declared bounds: close, used.
    r = vff.read_gltf_fields(glb_edit(asset / "x.glb", asset / "close.glb", nudge_box))
    close = r.fields[0]
    assert close.match == "close" and close.usable and close.bounds_difference == 0
    assert close.open().map_count == 26
    assert [p["rule"] for p in r.problems] == [14102, 14104]


def test_an_error_field(asset):
    r = vff.read_gltf_fields(glb_edit(asset / "x.glb", asset / "bad.glb",
                                      lambda j, b: ext(j, 1).update(mimeType="application/octet-stream")))
    assert r.has_error
    knot = r.fields[1]
    assert not knot.valid and not knot.usable and knot.bytes == b"" and knot.match == "unchecked"
    errors = [p for p in r.problems if p["severity"] == "error"]
    assert [(p["rule"], p["name"], p["path"]) for p in errors] == [
        (14008, "gltf-mime-type", "/meshes/1/extensions/VFF_visibility_field/mimeType")]
    with pytest.raises(vff.GltfError) as e:
        knot.open()
    assert e.value.code == 14008 and e.value.path == errors[0]["path"]
    assert r.fields[0].usable  # the other mesh is still read


def test_check_geometry_false(asset):
    r = vff.read_gltf_fields(str(asset / "x.glb"), check_geometry=False)
    box = r.fields[0]
    assert box.valid and box.match == "unchecked" and box.mesh_geometry_hash is None and not box.usable
    with pytest.raises(vff.GltfError, match="check_geometry"):
        box.open()


def test_file_problems_and_unreadable_files(tmp_path):
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"glTF\x02\x00\x00\x00garbage")
    r = vff.read_gltf_fields(str(junk))
    assert r.has_error and r.fields == [] and [p["rule"] for p in r.problems] == [14001]
    with pytest.raises(OSError):
        vff.read_gltf_fields(str(tmp_path / "missing.glb"))
    with pytest.raises(vff.IoError):
        vff.read_gltf_fields(str(tmp_path / "missing.glb"))


def test_a_uri_field(asset):
    box = (asset / "split" / "x.mesh0.vff").read_bytes()
    (asset / "box field.vff").write_bytes(box)

    def to_uri(j, b):
        e = ext(j, 0)
        del e["bufferView"]
        e["uri"] = "box%20field.vff"
    r = vff.read_gltf_fields(glb_edit(asset / "x.glb", asset / "uri.glb", to_uri))
    f = r.fields[0]
    assert f.uri == "box%20field.vff" and f.buffer_view is None and f.bytes == box and f.usable
    (asset / "box field.vff").unlink()
    r = vff.read_gltf_fields(str(asset / "uri.glb"))
    assert r.has_error and not r.fields[0].valid
    assert [p["rule"] for p in r.problems if p["severity"] == "error"] == [14007]
