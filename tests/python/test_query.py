"""vff.FieldQuery and vff.Instance: batches equal libvff's one-ray answers and vff-query's; errors."""
import io

import numpy as np
import pytest

import vff
from conftest import VECTORS, rays_around, vff_query

FIELDS = ["u8d-zstd-normals-meta", "u8c-stored-normals-3d-gutter1", "u16d-zstd-normals-gutter2", "bit1-stored",
          "bc4-zstd-normals-slices"]


def one_ray_answers(target, o, d, interpolated=False):
    rows = [target.intersect_ray(o[i], d[i], interpolated=interpolated) for i in range(len(o))]
    hit = np.array([r[0] for r in rows])
    t = np.array([r[1] for r in rows], np.float32)
    point = np.array([r[2] for r in rows], np.float32)
    normal = np.array([r[3] for r in rows], np.float32)
    vis = np.array([target.visibility_ray(o[i], d[i], interpolated=interpolated) for i in range(len(o))], np.float32)
    occ = np.array([target.occluded_ray(o[i], d[i], interpolated=interpolated) for i in range(len(o))])
    return hit, t, point, normal, vis, occ


def check_batch_equals_one_ray(target, o, d, interpolated):
    hit, t, point, normal, vis, occ = one_ray_answers(target, o, d, interpolated)
    h = target.intersect(o, d, interpolated=interpolated, threads=3)
    assert h.hit.dtype == np.bool_ and h.t.dtype == np.float32 and h.point.shape == (len(o), 3)
    assert np.array_equal(h.hit, hit)
    assert np.array_equal(h.t, t)
    assert np.array_equal(h.point, point, equal_nan=True)
    assert np.array_equal(h.normal, normal, equal_nan=True)
    assert np.array_equal(target.visibility(o, d, interpolated=interpolated, threads=2), vis)
    assert np.array_equal(target.occluded(o, d, interpolated=interpolated), occ)
    assert hit.any() and not hit.all()


def test_batch_equals_one_ray_nearest():
    for name in FIELDS:
        f = vff.open(str(VECTORS / "valid" / (name + ".vff")))
        o, d = rays_around(f.center, f.radius, 700, 1)
        check_batch_equals_one_ray(vff.FieldQuery(f), o, d, False)


def test_batch_equals_one_ray_interpolated():
    for name in FIELDS:
        f = vff.open(str(VECTORS / "valid" / (name + ".vff")))
        o, d = rays_around(f.center, f.radius, 400, 2)
        check_batch_equals_one_ray(vff.FieldQuery(f), o, d, True)


def test_instance_batch_equals_one_ray():
    f = vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff"))
    q = vff.FieldQuery(f)
    inst = vff.Instance.from_axis_angle(q, (0, 1, 0.5), 0.7, translation=(2, -1, 0.5), scale=1.5)
    (c, r) = inst.world_sphere
    assert r == pytest.approx(1.5 * f.radius)
    o, d = rays_around(c, r, 600, 3)
    check_batch_equals_one_ray(inst, o, d, False)
    check_batch_equals_one_ray(inst, o, d, True)
    # A matrix rotation gives the same instance as the axis-angle one.
    same = vff.Instance(q, inst.rotation, inst.translation, inst.scale)
    assert np.array_equal(same.intersect(o, d).t, inst.intersect(o, d).t)


def test_batch_equals_vff_query():
    path = VECTORS / "valid" / "u16d-zstd-normals-gutter2.vff"
    f = vff.open(str(path))
    o, d = rays_around(f.center, f.radius, 500, 4)
    buf = io.BytesIO()
    np.save(buf, np.hstack([o, d]).astype(np.float32))
    rc, out, err = vff_query(path, "--format", "npy", "--visibility", "--interpolated", stdin=buf.getvalue())
    assert rc == 0, err
    got = np.load(io.BytesIO(out))
    q = vff.FieldQuery(f)
    h = q.intersect(o, d, interpolated=True)
    assert np.array_equal(got[:, 0] == 1, h.hit)
    assert np.array_equal(got[:, 1], h.t)
    assert np.array_equal(got[:, 2:5], h.point, equal_nan=True)
    assert np.array_equal(got[:, 5:8], h.normal, equal_nan=True)
    assert np.array_equal(got[:, 8] == 1, h.inside)
    assert np.array_equal(got[:, 9], q.visibility(o, d, interpolated=True))


def test_bounds_layouts_and_threads():
    f = vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff"))
    q = vff.FieldQuery(f)
    o, d = rays_around(f.center, f.radius, 5000, 5)
    h = q.intersect(o, d)
    # Answers do not depend on the thread count, and any strides are read as the contiguous rays.
    assert np.array_equal(q.intersect(o, d, threads=1).t, h.t)
    wide = np.zeros((5000, 7), np.float32)
    wide[:, 1:4] = o
    fortran = np.asfortranarray(d)
    assert np.array_equal(q.intersect(wide[:, 1:4], fortran).t, h.t)
    assert np.array_equal(q.intersect(o[::-1], d[::-1]).t, h.t[::-1])
    # tmax as a number and as an array: a hit beyond it is a miss.
    tmax = np.where(h.hit, h.t * 0.5, np.float32(1e30)).astype(np.float32)
    assert not q.intersect(o, d, tmax=tmax).hit[h.hit & ~h.inside].any()
    tmin = np.zeros(5000, np.float32)
    assert np.array_equal(q.intersect(o, d, tmin).t, h.t)
    assert len(q.intersect(o[:0], d[:0])) == 0
    # out= fills the arrays of an earlier answer again.
    again = q.intersect(o[::-1], d[::-1])
    filled = q.intersect(o, d, out=again)
    assert filled.t is again.t or np.shares_memory(filled.t, again.t)
    assert np.array_equal(again.t, h.t) and np.array_equal(again.point, h.point, equal_nan=True)
    with pytest.raises(ValueError, match="out: holds 5000 rays, the call has 4"):
        q.intersect(o[:4], d[:4], out=again)


def test_bad_shapes_and_dtypes_raise_clear_errors():
    q = vff.FieldQuery(vff.open(str(VECTORS / "valid" / "u8d-stored.vff")))
    o = np.zeros((4, 3), np.float32)
    with pytest.raises(TypeError, match=r"origins: expected dtype float32, got float64"):
        q.intersect(o.astype(np.float64), o)
    with pytest.raises(TypeError, match=r"directions: expected a numpy float32 array of shape \(N, 3\), got list"):
        q.occluded(o, [[0, 0, 1]] * 4)
    with pytest.raises(ValueError, match=r"origins: expected shape \(N, 3\), got \(4, 2\)"):
        q.visibility(o[:, :2], o)
    with pytest.raises(ValueError, match=r"directions: expected shape \(N, 3\), got \(12,\)"):
        q.intersect(o, o.reshape(-1))
    with pytest.raises(ValueError, match="differ in length: 4 and 3"):
        q.intersect(o, o[:3])
    with pytest.raises(ValueError, match=r"tmax: expected shape \(4,\)"):
        q.intersect(o, o, tmax=np.ones(3, np.float32))
    with pytest.raises(TypeError, match="tmin: expected dtype float32"):
        q.intersect(o, o, tmin=np.ones(4))
    with pytest.raises(TypeError, match=r"tmax: expected None, a number or a float32 array of shape \(N,\)"):
        q.intersect(o, o, tmax="far")
    with pytest.raises(ValueError, match="scale"):
        vff.Instance(q, scale=0)
    with pytest.raises(ValueError, match="axis"):
        vff.Instance.from_axis_angle(q, (0, 0, 0), 1.0)


def test_queries_keep_their_file_alive():
    q = vff.FieldQuery(vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff")))
    inst = vff.Instance(q, translation=(1, 2, 3))
    del q
    import gc
    gc.collect()
    f = inst.field.file
    o = np.array([[f.center[0] + 1, f.center[1] + 2, f.center[2] + 3 + 4 * f.radius]], np.float32)
    assert inst.intersect(o, np.array([[0, 0, -1]], np.float32)).hit[0]
