#!/usr/bin/env python3
"""Ground ambient occlusion under the bunny, through a visibility field, against exact casts.

Bakes a mesh (the Stanford bunny by default) with vff.bake_file, then renders the ambient occlusion of
the ground plane under it with numpy, seen from above: for each pixel, cosine-weighted rays over the hemisphere up to
a range of R, answered by the field (nearest and interpolated) and by exact ray-triangle casts of
this script's own (numpy Moller-Trumbore over a two-level box hierarchy; no Embree). Writes the three
images side by side with the error map as a PNG, and a plot of the error against the exact value.

    PYTHONPATH=build/python python3 samples/python/ao.py --out out/python
    python3 samples/python/ao.py --mesh my.obj --size 96 --rays 32 --out out/python

Needs numpy and matplotlib (scripts/setup.sh installs them) and the vff module (build/python or an
installed one).
"""
import argparse
import os
import pathlib
import sys
import time

import numpy as np

import vff


def default_mesh():
    root = pathlib.Path(__file__).resolve().parents[2]
    for p in (root.parent / "shared" / "meshes" / "stanford-bunny.obj", pathlib.Path("/usr/share/glmark2/models/bunny.obj")):
        if p.exists():
            return str(p)
    return None


def load_obj(path):
    """Vertices (V, 3) and triangles (F, 3) of an OBJ (polygons fanned), for the exact casts."""
    v, f = [], []
    with open(path) as src:
        for line in src:
            if line.startswith("v "):
                v.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(tok.split("/")[0]) for tok in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(v) + i for i in idx]
                f.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return np.array(v, np.float64), np.array(f, np.int64)


class ExactTracer:
    """Any-hit ray casts against triangles: leaves of 64 triangles (sorted along a Morton curve) in
    groups of 32, each with its bounding box, tested with numpy slabs, then Moller-Trumbore."""

    def __init__(self, vertices, faces, leaf=64, group=32):
        tri = vertices[faces]  # (F, 3, 3)
        c = tri.mean(axis=1)
        lo, hi = c.min(0), c.max(0)
        q = ((c - lo) / np.maximum(hi - lo, 1e-12) * 1023).astype(np.uint64)
        code = np.zeros(len(c), np.uint64)
        for bit in range(10):
            for axis in range(3):
                code |= ((q[:, axis] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + axis)
        tri = tri[np.argsort(code, kind="stable")]
        self.leaves = [tri[i:i + leaf] for i in range(0, len(tri), leaf)]
        self.leaf_box = np.array([[t.reshape(-1, 3).min(0), t.reshape(-1, 3).max(0)] for t in self.leaves])
        self.groups = [list(range(i, min(i + group, len(self.leaves)))) for i in range(0, len(self.leaves), group)]
        self.group_box = np.array([[self.leaf_box[g, 0].min(0), self.leaf_box[g, 1].max(0)] for g in self.groups])

    @staticmethod
    def _slab(o, inv, box, tmax):
        t0 = (box[0] - o) * inv
        t1 = (box[1] - o) * inv
        near = np.nanmax(np.minimum(t0, t1), axis=1)
        far = np.nanmin(np.maximum(t0, t1), axis=1)
        return (near <= far) & (far >= 0) & (near <= tmax)

    @staticmethod
    def _triangles(o, d, tmax, tri):
        """(rays,) True where some triangle of tri (T, 3, 3) is hit with 0 < t <= tmax."""
        e1 = tri[:, 1] - tri[:, 0]
        e2 = tri[:, 2] - tri[:, 0]
        p = np.cross(d[:, None, :], e2[None])
        det = np.einsum("rtk,tk->rt", p, e1)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = o[:, None, :] - tri[None, :, 0]
        u = np.einsum("rtk,rtk->rt", s, p) * inv
        qv = np.cross(s, e1[None])
        v = np.einsum("rk,rtk->rt", d, qv) * inv
        t = np.einsum("tk,rtk->rt", e2, qv) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6) & (t <= tmax[:, None])
        return hit.any(axis=1)

    def occluded(self, o, d, tmax):
        o = o.astype(np.float64)
        d = d.astype(np.float64)
        tmax = np.broadcast_to(np.asarray(tmax, np.float64), (len(o),)).copy()
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
        out = np.zeros(len(o), bool)
        for gi, group in enumerate(self.groups):
            live = np.flatnonzero(~out)
            cand = live[self._slab(o[live], inv[live], self.group_box[gi], tmax[live])]
            for li in group:
                if len(cand) == 0:
                    break
                cand = cand[~out[cand]]
                near = cand[self._slab(o[cand], inv[cand], self.leaf_box[li], tmax[cand])]
                for k in range(0, len(near), 2048):
                    chunk = near[k:k + 2048]
                    out[chunk] |= self._triangles(o[chunk], d[chunk], tmax[chunk], self.leaves[li])
        return out


def ground_rays(field, ground, size, rays, seed=1):
    """Points on the ground (the plane under the object's lowest point, y up) over a square of side
    4R around its foot, each with `rays` cosine-weighted directions (stratified): (size*size*rays, 3)."""
    c = np.array(field.center, np.float64)
    r = field.radius
    xs = (np.arange(size) + 0.5) / size * 4 * r - 2 * r
    gx, gz = np.meshgrid(c[0] + xs, c[2] + xs)
    points = np.stack([gx, np.full_like(gx, ground), gz], -1).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    u1 = (np.arange(rays) + rng.random((len(points), rays))) / rays
    u2 = rng.random((len(points), rays))
    rad = np.sqrt(u1)
    phi = 2 * np.pi * u2
    d = np.stack([rad * np.cos(phi), np.sqrt(np.maximum(0, 1 - u1)), rad * np.sin(phi)], -1).reshape(-1, 3)
    o = np.repeat(points, rays, axis=0)
    o[:, 1] += 1e-4 * r
    return o.astype(np.float32), d.astype(np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesh", default=default_mesh(), help="an .obj mesh (default: the Stanford bunny)")
    ap.add_argument("--out", default="out/python", help="output folder")
    ap.add_argument("--size", type=int, default=96, help="image size in pixels")
    ap.add_argument("--rays", type=int, default=32, help="rays per pixel")
    ap.add_argument("--count", type=int, default=32, help="octa-hemi2 n of the bake (32: the paper's 4226 maps)")
    ap.add_argument("--map-size", type=int, default=64, help="map resolution M of the bake")
    ap.add_argument("--range", type=float, default=2.0, help="AO range, in multiples of R")
    a = ap.parse_args()
    if not a.mesh or not os.path.exists(a.mesh):
        print("ao.py: error: no mesh (give --mesh; the default bunny is ../shared/meshes/stanford-bunny.obj "
              "or Debian's glmark2-data)", file=sys.stderr)
        return 2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(a.out, exist_ok=True)
    t0 = time.perf_counter()
    field = vff.bake_file(a.mesh, os.path.join(a.out, "field.vff"), count=a.count, map_size=a.map_size)
    print("baked %s: %d maps of %dx%d in %.2f s" % (a.mesh, field.map_count, a.map_size, a.map_size,
                                                     time.perf_counter() - t0))
    vertices, faces = load_obj(a.mesh)
    o, d = ground_rays(field, float(vertices[:, 1].min()), a.size, a.rays)
    tmax = np.float32(a.range * field.radius)
    q = vff.FieldQuery(field)
    images, seconds = {}, {}
    for name, interpolated in (("nearest", False), ("interpolated", True)):
        t0 = time.perf_counter()
        vis = q.visibility(o, d, None, tmax, interpolated=interpolated, ray_origin="off-object")
        seconds[name] = time.perf_counter() - t0
        images[name] = vis.reshape(a.size, a.size, a.rays).mean(-1)
    t0 = time.perf_counter()
    tracer = ExactTracer(vertices, faces)
    # Rays that miss the bounding sphere within the range are unoccluded: only the others are cast.
    c = np.array(field.center, np.float32)
    oc = o - c
    b = np.sum(oc * d, axis=1)
    disc = b * b - (np.sum(oc * oc, axis=1) - field.radius ** 2)
    near = (disc >= 0) & (-b - np.sqrt(np.maximum(disc, 0)) <= tmax) & (-b + np.sqrt(np.maximum(disc, 0)) >= 0)
    blocked = np.zeros(len(o), bool)
    idx = np.flatnonzero(near)
    blocked[idx] = tracer.occluded(o[idx], d[idx], tmax)
    seconds["exact"] = time.perf_counter() - t0
    images["exact"] = (~blocked).reshape(a.size, a.size, a.rays).mean(-1)
    # Pixels under the object (a camera above sees the object there, not the ground) are left out,
    # as in vff-experiments ao: the ray straight up from their point hits the object.
    points = o[::a.rays]
    up = np.tile(np.array([[0, 1, 0]], np.float32), (len(points), 1))
    under = tracer.occluded(points, up, np.float32(4 * field.radius)).reshape(a.size, a.size)
    for k in images:
        images[k] = np.where(under, np.nan, images[k])

    ground = ~under
    rms = {k: float(np.sqrt(np.mean((images[k][ground] - images["exact"][ground]) ** 2)) * 255)
           for k in ("nearest", "interpolated")}
    for k in ("exact", "nearest", "interpolated"):
        extra = "" if k == "exact" else ", RMS %.2f (8-bit scale)" % rms[k]
        print("%-12s %d rays in %.3f s%s" % (k, len(o), seconds[k], extra))

    err = images["interpolated"] - images["exact"]
    fig, axes = plt.subplots(1, 4, figsize=(16, 4.4))
    for ax, k in zip(axes, ("exact", "nearest", "interpolated")):
        ax.imshow(images[k], cmap="gray", vmin=0, vmax=1, origin="lower")
        ax.set_title(k if k == "exact" else "%s (RMS %.2f)" % (k, rms[k]))
        ax.axis("off")
    lim = max(1e-3, float(np.nanmax(np.abs(err))))
    im = axes[3].imshow(err, cmap="RdBu", vmin=-lim, vmax=lim, origin="lower")
    axes[3].set_title("interpolated - exact")
    axes[3].axis("off")
    fig.colorbar(im, ax=axes[3], fraction=0.046)
    fig.tight_layout()
    png = os.path.join(a.out, "ao.png")
    fig.savefig(png + ".tmp.png", dpi=80)
    os.replace(png + ".tmp.png", png)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    for k, marker in (("nearest", "x"), ("interpolated", ".")):
        ax.scatter(images["exact"][ground], (images[k] - images["exact"])[ground], s=4, marker=marker,
                   label="%s, RMS %.2f" % (k, rms[k]), alpha=0.5)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("exact ambient visibility")
    ax.set_ylabel("field - exact")
    ax.legend()
    fig.tight_layout()
    plot = os.path.join(a.out, "ao-error.png")
    fig.savefig(plot + ".tmp.png", dpi=80)
    os.replace(plot + ".tmp.png", plot)
    plt.close(fig)
    print("wrote %s and %s" % (png, plot))
    return 0


if __name__ == "__main__":
    sys.exit(main())
