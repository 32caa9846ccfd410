"""vff.Scene and vff.load_scene: batches against the loop over the scene's instances."""
import os
import json

import numpy as np
import pytest

from conftest import VECTORS, rays_around

import vff


def fields():
    names = ["u8d-zstd-normals-meta", "bc4-zstd-normals-slices"]
    return [vff.FieldQuery(vff.open(str(VECTORS / "valid" / (n + ".vff")))) for n in names]


def placements():
    # Five instances of two fields, two of them overlapping, one rotated and scaled.
    return [(0, None, (0, 0, 0), 1.0), (1, None, (2.0, -1, 2), 1.0), (0, "rot", (-1.5, 0.5, 0), 0.7),
            (1, None, (-2, -1, 3), 1.3), (0, None, (6, 0, 0), 1.0)]


def rotation():
    c, s = np.cos(0.6), np.sin(0.6)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], np.float32)


def scene_rays(scene_instances, n, seed):
    centers = np.array([i.world_sphere[0] for i in scene_instances], np.float32)
    lo, hi = centers.min(0) - 3, centers.max(0) + 3
    rng = np.random.default_rng(seed)
    o = rng.uniform(lo, hi, (n, 3)).astype(np.float32)
    target = centers[rng.integers(0, len(centers), n)] + rng.uniform(-0.5, 0.5, (n, 3))
    d = (target - o).astype(np.float32)
    d[::7] = rng.uniform(-1, 1, (len(d[::7]), 3))  # some rays aimed anywhere
    return o, d


def loop_answers(instances, o, d, interpolated, tmax=None):
    """What the scene must answer: the loop over its instances in id order."""
    n = len(o)
    t = np.full(n, np.inf, np.float32)
    hit = np.zeros(n, bool)
    which = np.full(n, -1, np.int32)
    point = np.full((n, 3), np.nan, np.float32)
    occluded = np.zeros(n, bool)
    vis = np.ones(n, np.float32)
    for k, inst in enumerate(instances):
        h = inst.intersect(o, d, tmax=tmax, interpolated=interpolated)
        nearer = h.hit & (h.t < t)
        t[nearer], hit[nearer], which[nearer], point[nearer] = h.t[nearer], True, k, h.point[nearer]
        occluded |= inst.occluded(o, d, tmax=tmax, interpolated=interpolated)
        vis *= inst.visibility(o, d, tmax=tmax, interpolated=interpolated)
    return hit, t, which, point, occluded, vis


def build(qs):
    scene = vff.Scene()
    for k, (f, rot, tr, sc) in enumerate(placements()):
        if k == 2:
            assert scene.add(vff.Instance(qs[f], rotation(), tr, sc)) == k  # an Instance
        else:
            assert scene.add(qs[f], rotation=None, translation=tr, scale=sc) == k  # a FieldQuery and a placement
    return scene


@pytest.mark.parametrize("interpolated", [False, True])
def test_batches_equal_the_loop_over_instances(interpolated):
    qs = fields()
    scene = build(qs)
    scene.commit()
    instances = [scene.instance(k) for k in range(len(scene))]
    o, d = scene_rays(instances, 3000, 5)
    for tmax in (None, 2.0):
        hit, t, which, point, occ, vis = loop_answers(instances, o, d, interpolated, tmax)
        assert hit.any() and not hit.all() and len(set(which[hit])) >= 4, set(which[hit])
        h = scene.intersect(o, d, tmax=tmax, interpolated=interpolated, threads=3)
        assert np.array_equal(h.hit, hit) and np.array_equal(h.t, t) and np.array_equal(h.instance, which)
        assert np.array_equal(h.point, point, equal_nan=True)
        assert np.array_equal(scene.occluded(o, d, tmax=tmax, interpolated=interpolated, threads=2), occ)
        assert np.array_equal(scene.visibility(o, d, tmax=tmax, interpolated=interpolated, threads=1), vis)
    # The one-ray calls agree with the batch.
    h = scene.intersect(o, d, interpolated=interpolated)
    for r in range(0, 3000, 97):
        one = scene.intersect_ray(o[r], d[r], interpolated=interpolated)
        assert one[0] == h.hit[r] and one[5] == h.instance[r]
        if one[0]:
            assert np.float32(one[1]) == h.t[r]


@pytest.mark.parametrize("interpolated", [False, True])
def test_sources_equal_the_loop_with_each_rays_origin(interpolated):
    """With sources, the ray's own instance answers 'on-object' and every other 'off-object'."""
    qs = fields()
    scene = build(qs)
    scene.commit()
    instances = [scene.instance(k) for k in range(len(scene))]
    rng = np.random.default_rng(3)
    # Rays from inside the spheres (overlapping ones too), each with a source: its instance or none.
    n = 2000
    which = rng.integers(0, len(instances), n)
    centers = np.array([instances[k].world_sphere[0] for k in which], np.float32)
    radii = np.array([instances[k].world_sphere[1] for k in which], np.float32)
    o = (centers + rng.uniform(-0.5, 0.5, (n, 3)) * radii[:, None]).astype(np.float32)
    d = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
    sources = np.where(rng.uniform(size=n) < 0.5, which, -1).astype(np.int64)
    tmax = np.float32(0.8)
    want_occ = np.zeros(n, bool)
    want_vis = np.ones(n, np.float32)
    for k, inst in enumerate(instances):
        own = sources == k
        on = inst.occluded(o, d, tmax=tmax, interpolated=interpolated, ray_origin="on-object")
        off = inst.occluded(o, d, tmax=tmax, interpolated=interpolated, ray_origin="off-object")
        want_occ |= np.where(own, on, off)
        von = inst.visibility(o, d, tmax=tmax, interpolated=interpolated, ray_origin="on-object")
        voff = inst.visibility(o, d, tmax=tmax, interpolated=interpolated, ray_origin="off-object")
        want_vis *= np.where(own, von, voff)
    got = scene.occluded(o, d, tmax=tmax, interpolated=interpolated, sources=sources, threads=3)
    assert np.array_equal(got, want_occ) and want_occ.any() and not want_occ.all()
    assert np.array_equal(scene.visibility(o, d, tmax=tmax, interpolated=interpolated, sources=sources.astype(np.int32)),
                          want_vis)
    h = scene.intersect(o, d, tmax=tmax, interpolated=interpolated, sources=sources)
    assert np.array_equal(h.hit, want_occ)
    for r in range(0, n, 37):
        src = int(sources[r])
        assert scene.occluded_ray(o[r], d[r], 0.0, tmax, interpolated=interpolated, source=src) == want_occ[r]
        one = scene.intersect_ray(o[r], d[r], 0.0, tmax, interpolated=interpolated, source=src)
        assert one[0] == h.hit[r] and one[5] == h.instance[r]
    # Sources change the answers of rays that start inside another instance's sphere.
    plain = scene.occluded(o, d, tmax=tmax, interpolated=interpolated, intra_bias=0.0)
    assert not np.array_equal(plain, got)
    # Bad sources are named.
    with pytest.raises(ValueError, match=r"sources\[3\] = 9"):
        bad = sources.copy()
        bad[3] = 9
        scene.occluded(o, d, sources=bad)
    with pytest.raises(ValueError, match="one instance id"):
        scene.occluded(o, d, sources=sources[:5])
    with pytest.raises(TypeError, match="integer array"):
        scene.occluded(o, d, sources=sources.astype(np.float32))
    with pytest.raises(ValueError, match="source = 7"):
        scene.occluded_ray(o[0], d[0], source=7)
    with pytest.raises(ValueError, match="ray_origin"):
        instances[0].occluded(o, d, ray_origin="floor")


def test_moves_need_a_commit():
    qs = fields()
    scene = build(qs)
    with pytest.raises(vff.Error) as e:
        scene.intersect(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
    assert e.value.name == "bad-state"
    scene.commit()
    assert scene.committed
    o = np.array([[6.5, -1, 5]], np.float32)
    d = np.array([[0, 0, -1]], np.float32)
    before = scene.intersect(o, d)
    assert before.instance[0] == 4
    scene.set_transform(4, translation=(60, 0, 0))
    assert not scene.committed
    scene.commit()
    after = scene.intersect(o, d, out=before)  # (the arrays of the earlier call, filled again)
    assert after.instance is before.instance and before.instance[0] == -1 and not before.hit[0]
    assert scene.candidates((60.5, -1, 5), (0, 0, -1)) == [4]
    with pytest.raises(vff.Error):
        scene.set_transform(9, translation=(0, 0, 0))
    with pytest.raises(vff.InvalidArgumentError):
        scene.add(qs[0], rotation=np.eye(3, dtype=np.float32) * 2)
    with pytest.raises(TypeError, match="FieldQuery or a vff.Instance"):
        scene.add("bunny")


def test_fields_outlive_their_python_names():
    scene = vff.Scene()
    scene.add(fields()[0], translation=(0, 0, 0))  # the FieldQuery has no other reference
    scene.commit()
    h = scene.intersect(np.array([[0.5, -1, 5]], np.float32), np.array([[0, 0, -1]], np.float32))
    assert h.hit[0] and h.instance[0] == 0


def test_load_scene_equals_its_description(tmp_path):
    placed = [(0, (0, 0, 0), (0, 0, 0, 1), 1.0), (1, (2.5, 0, 0), (0, 0.2955202, 0, 0.9553365), 0.8),
              (0, (-2, 1, 0), (0, 0, 0, 1), 1.5)]
    doc = {"asset": {"format": "vff-scene", "version": 1},
           "fields": [{"uri": str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff"), "name": "a"},
                      {"uri": str(VECTORS / "valid" / "bc4-zstd-normals-slices.vff")}],
           "instances": [{"field": f, "name": "i%d" % k, "translation": list(t), "rotation": list(r), "scale": s}
                         for k, (f, t, r, s) in enumerate(placed)]}
    path = tmp_path / "s.vffscene.json"
    path.write_text(json.dumps(doc))
    scene = vff.load_scene(str(path))
    assert len(scene) == 3 and scene.committed and scene.names == ["i0", "i1", "i2"]
    instances = [scene.instance(k) for k in range(3)]
    assert np.allclose(instances[1].translation, (2.5, 0, 0)) and instances[2].scale == 1.5
    o, d = scene_rays(instances, 2000, 8)
    hit, t, which, _, occ, vis = loop_answers(instances, o, d, False)
    assert len(set(which[hit])) == 3, set(which[hit])
    h = scene.intersect(o, d)
    assert np.array_equal(h.t, t) and np.array_equal(h.instance, which)
    assert np.array_equal(scene.occluded(o, d), occ) and np.array_equal(scene.visibility(o, d), vis)
    with pytest.raises(TypeError):
        scene.add(instances[0])
    doc["instances"][0]["field"] = 5
    path.write_text(json.dumps(doc))
    with pytest.raises(vff.SceneError) as e:
        vff.load_scene(str(path))
    assert e.value.name == "scene-field-index" and e.value.code == 11005
    assert e.value.message == "%s: instances[0].field: index 5 is not one of the 2 fields" % path
    with pytest.raises(vff.IoError):
        vff.load_scene(str(tmp_path / "none.json"))


SCENE_VECTORS = VECTORS / "scene"


def scene_vectors(kind):
    return sorted(p for p in (SCENE_VECTORS / kind).glob("**/*.json") if not p.name.endswith(".expected.json"))


def test_scene_errors_are_scene_errors(tmp_path):
    # A scene description's problem is a vff.SceneError (a vff.Error), carrying the rule's ID, and
    # its message places a JSON syntax error at LINE:COLUMN.
    path = tmp_path / "bad.vffscene.json"
    path.write_bytes(b'{"asset": {"format": "vff-scene", "version": 1},\n "fields": [,]}')
    with pytest.raises(vff.SceneError) as e:
        vff.load_scene(str(path))
    assert isinstance(e.value, vff.Error) and not isinstance(e.value, vff.MeshError)
    assert (e.value.code, e.value.name) == (11001, "scene-json")
    assert e.value.message.startswith("%s:2:13: fields[0]: syntax error" % path), e.value.message
    assert str(e.value).startswith("scene-json (11001): ")


def test_scene_description_must_be_a_regular_file(tmp_path):
    # A named pipe is refused at once (io-open), as File.open refuses it, instead of waiting for a
    # writer (a regression hangs until ctest's limit).
    fifo = tmp_path / "pipe.vffscene.json"
    os.mkfifo(fifo)
    with pytest.raises(vff.IoError) as e:
        vff.load_scene(str(fifo))
    assert e.value.code == 1001 and e.value.message == "%s: not a regular file" % fifo
    with pytest.raises(vff.IoError) as e:
        vff.load_scene(str(tmp_path))
    assert e.value.code == 1001


def test_scene_vectors_invalid():
    # Every invalid vector raises the ID of its folder; one failure line per vector.
    vectors = scene_vectors("invalid")
    assert len(vectors) >= 30
    failures = []
    for path in vectors:
        want = int(path.parent.name)
        try:
            vff.load_scene(str(path))
            failures.append("%s: accepted" % path.relative_to(SCENE_VECTORS))
        except vff.SceneError as e:
            if e.code != want or not e.message.startswith(str(path) + ":"):
                failures.append("%s: %s (%d): %s" % (path.relative_to(SCENE_VECTORS), e.name, e.code, e.message))
    assert not failures, "\n".join(failures)


def test_scene_vectors_valid():
    # The valid vectors whose fields all exist load, and place their instances as expected.json says;
    # the others fail only at opening a field (an I/O error, not a scene error).
    vectors = scene_vectors("valid")
    assert len(vectors) >= 8
    failures, loaded = [], 0
    for path in vectors:
        want = json.loads(path.with_name(path.stem + ".expected.json").read_text())
        name = str(path.relative_to(SCENE_VECTORS))
        if not all(f["exists"] for f in want["fields"]):
            with pytest.raises(vff.IoError):
                vff.load_scene(str(path))
            continue
        scene = vff.load_scene(str(path))
        loaded += 1
        if len(scene) != len(want["instances"]):
            failures.append("%s: %d instances" % (name, len(scene)))
            continue
        for k, w in enumerate(want["instances"]):
            got = scene.instance(k)
            c, r = got.world_sphere
            if list(np.float32(got.translation)) != list(np.float32(w["translation"])) or \
                    np.float32(got.scale) != np.float32(w["scale"]):
                failures.append("%s: instances[%d] placed at %s, scale %r" % (name, k, got.translation, got.scale))
            if not (np.allclose(c, w["worldSphere"]["center"], rtol=1e-5, atol=1e-5)
                    and np.isclose(r, w["worldSphere"]["radius"], rtol=1e-5)):
                failures.append("%s: instances[%d] world sphere %s, %r" % (name, k, c, r))
    assert loaded >= 4
    assert not failures, "\n".join(failures)


def test_scene_vectors_are_generated():
    # The committed vectors are what generate.py makes (it is deterministic).
    import subprocess
    import sys
    r = subprocess.run([sys.executable, str(SCENE_VECTORS / "generate.py"), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_stubs_name_every_public_name():
    # python/vff/__init__.pyi is the manual's index: every name of vff.__all__, and every public
    # member of the query classes, has a stub.
    import ast
    import pathlib
    tree = ast.parse((pathlib.Path(vff.__file__).parent / "__init__.pyi").read_text())
    top, members, bases = set(), {}, {}
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {n.name if isinstance(n, ast.FunctionDef) else n.target.id
                                  for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))}
            bases[node.name] = [b.id for b in node.bases if isinstance(b, ast.Name)]
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
        elif isinstance(node, ast.Assign):
            top.update(t.id for t in node.targets)
    assert set(vff.__all__) <= top, set(vff.__all__) - top

    def stubbed(cls):  # a class's stubbed members with those of its stub base classes (_Queries, ...)
        return members[cls].union(*(stubbed(b) for b in bases[cls] if b in members))

    for cls in ("Scene", "FieldQuery", "Instance", "Hits"):
        public = {n for n in dir(getattr(vff, cls)) if not n.startswith("_")}
        assert public <= stubbed(cls), (cls, public - stubbed(cls))
