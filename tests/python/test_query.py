"""vff.FieldQuery and vff.Instance: batches equal libvff's one-ray answers and vff-query's; errors."""
import io

import numpy as np
import pytest

import vff
from conftest import VECTORS, rays_around, vff_query

FIELDS = ["u8d-zstd-normals-meta", "u8c-stored-normals-3d-gutter1", "u16d-zstd-normals-gutter2", "bit1-stored",
          "bc4-zstd-normals-slices"]


def one_ray_answers(target, o, d, interpolated=False, refined=False):
    kw = dict(interpolated=interpolated, refined=refined)
    rows = [target.intersect_ray(o[i], d[i], **kw) for i in range(len(o))]
    hit = np.array([r[0] for r in rows])
    t = np.array([r[1] for r in rows], np.float32)
    point = np.array([r[2] for r in rows], np.float32)
    normal = np.array([r[3] for r in rows], np.float32)
    vis = np.array([target.visibility_ray(o[i], d[i], **kw) for i in range(len(o))], np.float32)
    occ = np.array([target.occluded_ray(o[i], d[i], **kw) for i in range(len(o))])
    return hit, t, point, normal, vis, occ


def check_batch_equals_one_ray(target, o, d, interpolated, refined=False):
    hit, t, point, normal, vis, occ = one_ray_answers(target, o, d, interpolated, refined)
    kw = dict(interpolated=interpolated, refined=refined)
    h = target.intersect(o, d, threads=3, **kw)
    assert h.hit.dtype == np.bool_ and h.t.dtype == np.float32 and h.point.shape == (len(o), 3)
    assert np.array_equal(h.hit, hit)
    assert np.array_equal(h.t, t)
    assert np.array_equal(h.point, point, equal_nan=True)
    assert np.array_equal(h.normal, normal, equal_nan=True)
    assert np.array_equal(target.visibility(o, d, threads=2, **kw), vis)
    assert np.array_equal(target.occluded(o, d, **kw), occ)
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


def test_batch_equals_one_ray_refined():
    for name in ["u8d-refined", "u8c-zstd-normals-meta-refined"]:
        f = vff.open(str(VECTORS / "valid" / (name + ".vff")))
        q = vff.FieldQuery(f)
        assert q.refined and q.refinement_bytes > 0
        o, d = rays_around(f.center, f.radius, 500, 4)
        check_batch_equals_one_ray(q, o, d, False, refined=True)
        inst = vff.Instance.from_axis_angle(q, (1, 0, 0.5), 0.4, translation=(0, 2, 0))
        (c, r) = inst.world_sphere
        o, d = rays_around(c, r, 300, 5)
        check_batch_equals_one_ray(inst, o, d, False, refined=True)
    plain = vff.FieldQuery(vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff")))
    assert not plain.refined and plain.refinement_bytes == 0
    with pytest.raises(ValueError, match="give one reconstruction, not both"):
        plain.intersect_ray((0, 0, 5), (0, 0, -1), interpolated=True, refined=True)


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
    assert np.array_equal(got[:, 12], q.visibility(o, d, interpolated=True))


def test_vff_query_sites_are_the_texels_read():
    # vff-query's sample, i, j: for a nearest hit from outside the sphere, the texel's decoded
    # distance from the entry point gives the hit's t; a ray that misses the sphere has none.
    path = VECTORS / "valid" / "u16d-zstd-normals-gutter2.vff"
    f = vff.open(str(path))
    o, d = rays_around(f.center, f.radius, 600, 9)
    o[-1], d[-1] = np.float32(f.center) + 5 * f.radius, (1, 0, 0)  # misses the sphere
    buf = io.BytesIO()
    np.save(buf, np.hstack([o, d]).astype(np.float32))
    rc, out, err = vff_query(path, "--format", "npy", stdin=buf.getvalue())
    assert rc == 0, err
    got = np.load(io.BytesIO(out))
    assert got.shape == (600, 12)
    assert (got[-1, 9:12] == -1).all()
    sample, i, j = got[:, 9].astype(int), got[:, 10].astype(int), got[:, 11].astype(int)
    m = f.map_resolution
    assert (sample[:-1] >= 0).all() and (sample < f.map_count).all() and (i < m).all() and (j < m).all()
    length = np.linalg.norm(d.astype(np.float64), axis=1)
    w = d / length[:, None]
    delta = o.astype(np.float64) - np.asarray(f.center, np.float64)
    beta = np.einsum("ij,ij->i", delta, w)
    entry = -beta - np.sqrt(np.maximum(beta**2 - (np.einsum("ij,ij->i", delta, delta) - f.radius**2), 0))
    checked = 0
    for r in np.flatnonzero((got[:, 0] == 1) & (got[:, 8] == 0) & (entry > 0)):
        dist = f.distances(sample[r])[j[r], i[r]]
        assert np.isfinite(dist), r
        assert abs(got[r, 1] * length[r] - (entry[r] + dist)) < 1e-3 * f.radius, r
        checked += 1
    assert checked > 100
    # The Python batch names the same sites, and one placed instance the same as its field.
    q = vff.FieldQuery(f)
    ks, ij = q.sites(o, d, threads=3)
    assert ks.dtype == np.int32 and ij.shape == (600, 2)
    assert np.array_equal(ks, got[:, 9].astype(np.int32)) and np.array_equal(ij, got[:, 10:12].astype(np.int32))
    moved = vff.Instance(q, None, (4, 5, 6), 2.0)
    mk, mij = moved.sites(o * 2 + np.float32([4, 5, 6]), d, threads=2)
    assert np.array_equal(mk, ks) and np.array_equal(mij, ij)


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


def test_large_batches_own_their_arrays():
    # Batches large enough for the huge-page blocks (and their reuse once released): every array
    # keeps its answers while later batches run, and a reused block answers afresh.
    f = vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff"))
    q = vff.FieldQuery(f)
    o, d = rays_around(f.center, f.radius, 120000, 21)
    first = q.intersect(o, d, threads=3)
    keep = first.t.copy(), first.point.copy(), first.hit.copy()
    assert first.hit.any() and not first.hit.all()
    other = q.intersect(o[::-1].copy(), d[::-1].copy(), threads=2)
    assert not np.shares_memory(first.t, other.t)
    assert np.array_equal(first.t, keep[0]) and np.array_equal(first.hit, keep[2])
    assert np.array_equal(first.point, keep[1], equal_nan=True)
    assert np.array_equal(other.t, keep[0][::-1])
    del first
    again = q.intersect(o, d, threads=1)  # (may land in the released block)
    assert np.array_equal(again.t, keep[0]) and np.array_equal(again.hit, keep[2])
    assert np.array_equal(again.point, keep[1], equal_nan=True)
    vis = q.visibility(o, d)
    occ = q.occluded(o, d)
    assert vis.shape == (120000,) and vis.dtype == np.float32 and occ.dtype == np.bool_
    assert np.array_equal(occ, keep[2]) and np.array_equal(vis == 0, keep[2])


def npy_bytes(*columns):
    buf = io.BytesIO()
    np.save(buf, np.hstack(columns).astype(np.float32))
    return buf.getvalue()


def test_bad_rays_raise_like_vff_query():
    # One rule for the batch and the command (python/vff/__init__.pyi, tools/vff-query/README.md): a
    # ray with a non-finite origin or direction, a zero direction, a NaN bound or tmin > tmax is
    # refused, naming the first one, and nothing is answered.
    path = VECTORS / "valid" / "u8d-stored.vff"
    f = vff.open(str(path))
    q = vff.FieldQuery(f)
    inst = vff.Instance(q, translation=(1, 2, 3))
    o, d = rays_around(f.center, f.radius, 40000, 31)
    tmin, tmax = np.zeros(40000, np.float32), np.full(40000, np.inf, np.float32)
    cases = []  # (origins, directions, tmin, tmax, message)
    bad_d = d.copy()
    bad_d[33000] = 0
    cases.append((o, bad_d, tmin, tmax, "ray 33000: the direction is zero"))
    bad_o = o.copy()
    bad_o[20001, 1] = np.nan
    bad_o[39000, 0] = np.inf
    cases.append((bad_o, bad_d, tmin, tmax, "ray 20001: the origin is not finite"))
    inf_d = d.copy()
    inf_d[7, 2] = -np.inf
    cases.append((o, inf_d, tmin, tmax, "ray 7: the direction is not finite"))
    crossed = tmax.copy()
    crossed[5] = -1
    cases.append((o, d, tmin, crossed, "ray 5: tmin is greater than tmax"))
    nan_min = tmin.copy()
    nan_min[39999] = np.nan
    cases.append((o, d, nan_min, tmax, "ray 39999: tmin or tmax is NaN"))
    for co, cd, cmin, cmax, message in cases:
        for target in (q, inst):
            for call in (target.intersect, target.occluded, target.visibility, target.sites):
                with pytest.raises(ValueError, match="^" + message + "$"):
                    call(co, cd, cmin, cmax, threads=3)
        # vff-query refuses the same ray: the row and the problem (exit 3, nothing written).
        rc, out, err = vff_query(path, "--format", "npy", stdin=npy_bytes(co, cd, cmin[:, None], cmax[:, None]))
        row, problem = message[len("ray "):].split(": ", 1)
        assert rc == 3 and out == b"", err
        assert "row " + row + ", column " in err and problem in err, err
    # A scalar NaN bound names ray 0; the one-ray calls refuse the same rays.
    with pytest.raises(ValueError, match="^ray 0: tmin or tmax is NaN$"):
        q.intersect(o, d, tmax=float("nan"))
    with pytest.raises(ValueError, match="^ray: the direction is zero$"):
        q.intersect_ray((0, 0, 5), (0, 0, 0))
    with pytest.raises(ValueError, match="^ray: the origin is not finite$"):
        inst.occluded_ray((np.nan, 0, 5), (0, 0, -1))
    with pytest.raises(ValueError, match="^ray: tmin is greater than tmax$"):
        q.visibility_ray((0, 0, 5), (0, 0, -1), 2.0, 1.0)
    # A Scene refuses them too, in its batches and its one-ray calls.
    scene = vff.Scene()
    scene.add(q, translation=(1, 2, 3))
    scene.commit()
    with pytest.raises(ValueError, match="^ray 33000: the direction is zero$"):
        scene.intersect(o, bad_d)
    with pytest.raises(ValueError, match="^ray: the direction is zero$"):
        scene.occluded_ray((0, 0, 5), (0, 0, 0))
    # out= keeps its answers when the call is refused; the good rays alone are answered.
    h = q.intersect(o, d)
    keep = h.t.copy()
    with pytest.raises(ValueError, match="^ray 6999: the direction is zero$"):  # (39999 - 33000, reversed)
        q.intersect(o[::-1], bad_d[::-1], out=h)
    assert np.array_equal(h.t, keep)
    ok = np.isfinite(bad_o).all(1) & np.isfinite(bad_d).all(1) & bad_d.any(1)
    assert ok.sum() == 40000 - 3
    assert np.array_equal(q.intersect(bad_o[ok], bad_d[ok]).t, keep[ok])


def test_integer_arguments_out_of_range_raise_value_errors():
    f = vff.open(str(VECTORS / "valid" / "u8d-stored.vff"))
    q = vff.FieldQuery(f)
    o, d = rays_around(f.center, f.radius, 10, 32)
    for call in (q.intersect, q.occluded, q.visibility, q.sites):
        with pytest.raises(ValueError, match=r"^threads: expected an integer >= 0 \(0: all cores\), got -1$"):
            call(o, d, threads=-1)
    last = f.map_count - 1
    for call in (f.map, f.distances):
        for index in (-1, f.map_count):
            with pytest.raises(IndexError, match=r"^index: map %d out of range \[0, %d\]: the field has %d maps$"
                               % (index, last, f.map_count)):
                call(index)
    assert f.map(last).shape == f.map(0).shape
