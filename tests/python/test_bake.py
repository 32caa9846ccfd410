"""vff.bake, vff.bake_file, compress/decompress/convert: fields baked from numpy meshes."""
import _thread
import threading
import time

import numpy as np
import pytest

import vff


def uv_sphere(radius=1.0, rings=24, segments=48, center=(0.0, 0.0, 0.0)):
    """A closed UV sphere: (V, 3) float32 vertices and (F, 3) int32 faces."""
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    v = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3) * radius
    v = (v + np.asarray(center)).astype(np.float32)
    faces = []
    for r in range(rings):
        for s in range(segments):
            a, b = r * segments + s, r * segments + (s + 1) % segments
            c, d = a + segments, b + segments
            if r > 0:
                faces.append((a, c, b))
            if r < rings - 1:
                faces.append((b, c, d))
    return v, np.array(faces, np.int32)


def ray_sphere(o, d, center, radius):
    """The first t >= 0 where unit-direction rays o + t d cross a sphere (inf for a miss)."""
    oc = o - np.asarray(center)
    b = np.sum(oc * d, axis=1)
    disc = b * b - (np.sum(oc * oc, axis=1) - radius * radius)
    t = -b - np.sqrt(np.maximum(disc, 0))
    return np.where((disc >= 0) & (t >= 0), t, np.inf)


def test_bake_answers_the_spheres():
    # A ball and a small moon: the bounding sphere is larger than the ball, so distances are real.
    ball, moon = ((0.5, -0.25, 2.0), 0.6), ((1.6, -0.25, 2.0), 0.1)
    v1, f1 = uv_sphere(ball[1], center=ball[0])
    v2, f2 = uv_sphere(moon[1], 8, 16, center=moon[0])
    v, f = np.vstack([v1, v2]), np.vstack([f1, f2 + len(v1)])
    calls = []
    field = vff.bake(v, f, count=12, map_size=32, normals=True, progress=lambda d, t: calls.append((d, t)))
    assert field.map_count == 2 * (2 * 144 + 24 + 1) and field.map_resolution == 32 and field.has_normals
    assert calls and calls[-1] == (field.map_count, field.map_count)
    assert field.validate() == []
    q = vff.FieldQuery(field)
    rng = np.random.default_rng(9)
    n = 2000
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = (np.array(field.center) + 3.0 * field.radius * dirs).astype(np.float32)
    d = (np.array(ball[0]) + rng.uniform(-0.3, 0.3, (n, 3)) - origins).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    exact = np.minimum(ray_sphere(origins, d, *ball), ray_sphere(origins, d, *moon))
    step = 2 * field.radius / 254  # one unorm8-diameter code
    for interpolated, median, p95 in ((False, 3 * step, 12 * step), (True, 2 * step, 8 * step)):
        h = q.intersect(origins, d, interpolated=interpolated)
        agree = h.hit == np.isfinite(exact)
        assert agree.mean() > 0.99
        both = h.hit & np.isfinite(exact)
        err = np.abs(h.t[both] - exact[both])
        assert np.median(err) < median and np.percentile(err, 95) < p95, (interpolated, np.median(err) / step)
    # Normals point away from the ball's centre where the ball was hit.
    h = q.intersect(origins, d)
    on_ball = h.hit & (ray_sphere(origins, d, *ball) <= ray_sphere(origins, d, *moon))
    radial = h.point[on_ball] - np.array(ball[0])
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.median(np.sum(radial * h.normal[on_ball], axis=1)) > 0.95


def ray_mesh(o, d, v, f, chunk=128):
    """Whether rays o + t d (t >= 0) meet triangles (v, f): Moller-Trumbore over every triangle."""
    a, e1, e2 = v[f[:, 0]], v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    out = np.zeros(len(o), bool)
    for s in range(0, len(o), chunk):
        oo, dd = o[s:s + chunk, None, :], d[s:s + chunk, None, :]
        p = np.cross(dd, e2)
        det = np.sum(e1 * p, -1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = oo - a
            u = np.sum(tv * p, -1) * inv
            q = np.cross(tv, e1)
            w = np.sum(dd * q, -1) * inv
            t = np.sum(e2 * q, -1) * inv
        out[s:s + chunk] = np.any((det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t >= 0), axis=1)
    return out


def test_bake_refined_answers_as_the_mesh(tmp_path):
    # refine=True stores the refinement (REFN); refined=True then answers the rays the maps are
    # unsure of by casting through the mesh: hit or miss as the triangles say, far more often than
    # the nearest maps.
    ball, moon = ((0.5, -0.25, 2.0), 0.6), ((1.6, -0.25, 2.0), 0.1)
    v1, f1 = uv_sphere(ball[1], 12, 24, center=ball[0])
    v2, f2 = uv_sphere(moon[1], 6, 12, center=moon[0])
    v, f = np.vstack([v1, v2]), np.vstack([f1, f2 + len(v1)])
    field = vff.bake(v, f, count=4, map_size=16, refine=True)
    assert field.validate() == []
    q = vff.FieldQuery(field)
    assert q.refined and q.refinement_bytes > 0
    rng = np.random.default_rng(4)
    n = 3000
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = (np.array(field.center) + 3.0 * field.radius * dirs).astype(np.float32)
    target = np.array(field.center) + rng.uniform(-1, 1, (n, 3)) * field.radius
    d = (target - origins).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    exact = ray_mesh(origins.astype(np.float64), d.astype(np.float64), v.astype(np.float64), f)
    assert 0.1 < exact.mean() < 0.9
    wrong_nearest = np.count_nonzero(q.occluded(origins, d) != exact)
    wrong_refined = np.count_nonzero(q.occluded(origins, d, refined=True) != exact)
    assert wrong_refined <= max(1, wrong_nearest // 10), (wrong_refined, wrong_nearest)
    assert np.array_equal(q.intersect(origins, d, refined=True).hit, q.occluded(origins, d, refined=True))
    plain = vff.FieldQuery(vff.bake(v, f, count=4, map_size=16))
    assert not plain.refined
    with pytest.raises(ValueError, match="refine_probe goes with refine=True"):
        vff.bake(v, f, count=1, map_size=4, refine_probe=True)
    with pytest.raises(ValueError, match="refine needs distances"):
        vff.bake(v, f, count=1, map_size=8, encoding="bit1", refine=True)


def test_bake_file_and_rewrites(tmp_path):
    v, f = uv_sphere(rings=8, segments=16)
    obj = tmp_path / "ball.obj"
    with open(obj, "w") as out:
        out.writelines("v %.9g %.9g %.9g\n" % tuple(p) for p in v)
        out.writelines("f %d %d %d\n" % tuple(t + 1) for t in f)
    baked = vff.bake_file(str(obj), str(tmp_path / "ball.vff"), count=2, map_size=8, threads=1)
    assert baked.path == str(tmp_path / "ball.vff") and baked.metadata["vff.source"]["name"] == "ball.obj"
    again = vff.bake(v, f, str(tmp_path / "mem.vff"), count=2, map_size=8, threads=2)
    assert np.array_equal(again.maps(), baked.maps())  # the thread count does not change the field
    small = vff.compress(str(tmp_path / "ball.vff"), str(tmp_path / "small.vff"))
    assert set(small.describe()["planes"]["distance"]["block_codecs"]) == {"zstd"}
    plain = vff.decompress(str(tmp_path / "small.vff"), str(tmp_path / "plain.vff"))
    assert np.array_equal(plain.maps(), baked.maps()) and plain.metadata == baked.metadata
    packed = vff.convert(str(tmp_path / "ball.vff"), str(tmp_path / "packed.vff"), max_texture_size=16, target="3d")
    assert packed.layout["target"] == "3d" and packed.layout["slice_width"] <= 16
    assert np.array_equal(packed.maps(), baked.maps()) and packed.validate() == []


def test_bake_errors():
    v, f = uv_sphere(rings=4, segments=8)
    with pytest.raises(vff.MeshError) as e:
        vff.bake(v, f + 1000)
    assert e.value.code == 10007
    bad = v.copy()
    bad[0, 0] = np.nan
    with pytest.raises(vff.MeshError) as e:
        vff.bake(bad, f)
    assert e.value.name == "mesh-non-finite"
    with pytest.raises(ValueError, match="encoding: expected one of unorm8-diameter"):
        vff.bake(v, f, encoding="unorm9")
    with pytest.raises(TypeError, match="unexpected keyword argument 'mapsize'"):
        vff.bake(v, f, mapsize=8)
    with pytest.raises(ValueError, match=r"vertices: expected shape \(V, 3\)"):
        vff.bake(v[:, :2], f)
    with pytest.raises(TypeError, match="faces: expected an integer array"):
        vff.bake(v, f.astype(np.float32))
    with pytest.raises(vff.IoError):
        vff.bake_file("/nonexistent/mesh.obj", "/nonexistent/out.vff")


def test_bake_stops_on_ctrl_c_and_on_callback_errors():
    v, f = uv_sphere(rings=48, segments=96)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        vff.bake(v, f, count=48, map_size=64)
    timer.join()
    assert time.monotonic() - start < 10

    def stop(done, total):
        raise RuntimeError("enough after %d of %d" % (done, total))

    with pytest.raises(RuntimeError, match="enough after"):
        vff.bake(v, f, count=48, map_size=64, progress=stop)


def test_bake_integer_options_out_of_range_name_their_range():
    # vff-bake's ranges (-m 1..4096, -j >= 0, ...), as ValueErrors naming the option, before anything
    # is baked; a non-integer is a TypeError.
    v, f = uv_sphere(rings=4, segments=8)
    cases = [({"map_size": 0}, r"map_size: expected an integer in \[1, 4096\], got 0"),
             ({"map_size": 4097}, r"map_size: expected an integer in \[1, 4096\], got 4097"),
             ({"threads": -1}, r"threads: expected an integer >= 0 \(0: all cores\), got -1"),
             ({"count": -1}, r"count: expected an integer >= 0 \(0: the scheme's default\), got -1"),
             ({"zstd_level": 0}, r"zstd_level: expected an integer in \[1, 22\], got 0"),
             ({"gutter": 65}, r"gutter: expected an integer in \[0, 64\], got 65"),
             ({"max_layers": 0}, r"max_layers: expected an integer in \[1, 65536\], got 0")]
    for kw, message in cases:
        with pytest.raises(ValueError, match="^" + message + "$"):
            vff.bake(v, f, **{"count": 2, "map_size": 8, **kw})
    with pytest.raises(ValueError, match=r"^map_size: expected an integer in \[1, 4096\], got 0$"):
        vff.bake_file("/nonexistent/mesh.obj", "/nonexistent/out.vff", map_size=0)
    with pytest.raises(TypeError, match="^map_size: expected an integer, got float$"):
        vff.bake(v, f, map_size=8.5)
    assert vff.bake(v, f, count=1, map_size=4, threads=1).map_resolution == 4


def test_bake_file_warns_what_a_gltf_loses(tmp_path):
    # A tetrahedron that requires a material extension and whose node has a skin: baked, with
    # vff-bake's warnings as UserWarnings naming the file.
    import base64
    import json
    data = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1], np.float32).tobytes() + \
        np.array([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3], np.uint16).tobytes()
    doc = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_texture_transform"],
           "extensionsRequired": ["KHR_texture_transform"],
           "buffers": [{"byteLength": len(data),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
           "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 1]},
                         {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "nodes": [{"name": "Body", "mesh": 0, "skin": 0}, {"name": "Root"}], "skins": [{"joints": [1]}],
           "scenes": [{"nodes": [0, 1]}], "scene": 0}
    path = tmp_path / "t.gltf"
    path.write_text(json.dumps(doc))
    with pytest.warns(UserWarning) as record:
        field = vff.bake_file(str(path), str(tmp_path / "t.vff"), count=1, map_size=8)
    assert [str(w.message) for w in record] == [
        str(path) + ": requires the glTF extension KHR_texture_transform, which changes no geometry: not read",
        str(path) + ": node 0 'Body' (mesh 0) has skin 0: baked in its bind pose, not posed by its joints"]
    assert field.map_count == 10 and field.map_resolution == 8
