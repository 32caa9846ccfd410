#!/usr/bin/env python3
"""The Python batch and vff-query against libvff's C++ batch, on the same rays, in one run.

    PYTHONPATH=build/python python3 benchmarks/python_query.py --field out/bunny.vff \\
        --query build/tools/vff-query/vff-query [--rays 1000000] [--repeat 5] [--quick]

Makes `--rays` ambient-occlusion rays about the field (origins on a disc around its foot, up to
2R, cosine-weighted; as vff-experiments bench's "ao" set) and writes them as an (N, 6) float32
.npy. Then, best of --repeat each, alternating:
  C++ batch    vff-query --timing: FieldQuery::intersect on the rays as vff::Ray in memory, the field
               opened by File::open (mapped, as a C++ caller and the Python module open it), in chunks
               over its threads, every answer kept in an array of all of them (as a C++ caller
               holds them), warm: the baseline of every ratio; and the same calls with each chunk's
               answers dropped (they never leave the cache: a bound, not a use)
  vff-query    the same command end to end, as a shell runs it (process start, opening the field with
               its checksums, reading the .npy, querying, writing the answers .npy), with the lookup
               sites (the default), with --no-sites, and with --columns hit,t (the least to write)
  I/O floor    reading the rays file and writing the answers' bytes, through the page cache, in
               Python: what vff-query's reading and writing cannot beat
  one ray      vff-query answering one --ray: its fixed cost (process start, the field opened and
               its checksums verified); with the I/O floor and the C++ batch, one after another, the
               rate of a vff-query that did nothing else (a bound for this tool as it runs its parts
               in turn, not for one that overlaps its I/O with the query)
  Python       FieldQuery.intersect(origins, directions) on numpy arrays (threads as vff-query's),
               warm (after an untimed call), with new answer arrays and with out= (arrays reused),
               and FieldQuery.occluded for reference
and prints each in Mrays/s with its ratio to the C++ batch, naming the CPU. Each ratio is the
path's rate over the C++ batch's, on the same rays and the same field, both the best of --repeat
runs taken alternately in this one run. --quick: 20000 rays, one run (a check of the chain).
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

import vff

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report import cpu_name  # noqa: E402


def ao_rays(field, n, seed=7):
    rng = np.random.default_rng(seed)
    c = np.array(field.center, np.float64)
    r = field.radius
    rad = 2 * r * np.sqrt(rng.random(n))
    phi = 2 * np.pi * rng.random(n)
    o = np.stack([c[0] + rad * np.cos(phi), np.full(n, c[1] - r + 1e-4 * r), c[2] + rad * np.sin(phi)], -1)
    u1, u2 = rng.random(n), rng.random(n)
    s = np.sqrt(u1)
    d = np.stack([s * np.cos(2 * np.pi * u2), np.sqrt(1 - u1), s * np.sin(2 * np.pi * u2)], -1)
    return o.astype(np.float32), d.astype(np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--field", required=True)
    ap.add_argument("--query", required=True, help="the vff-query executable")
    ap.add_argument("--rays", type=int, default=1000000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--interpolated", action="store_true")
    ap.add_argument("--quick", action="store_true", help="20000 rays, one run: the figures mean nothing")
    a = ap.parse_args()
    if a.quick:
        a.rays, a.repeat = 20000, 1
    f = vff.open(a.field)
    q = vff.FieldQuery(f)
    o, d = ao_rays(f, a.rays)
    extra = ["--interpolated"] if a.interpolated else []
    best = {"cpp": 0.0, "dropped": 0.0, "cli": 0.0, "nosites": 0.0, "hitt": 0.0, "floor": 0.0, "py": 0.0, "reuse": 0.0,
            "occ": 0.0, "one": float("inf")}
    reuse = q.intersect(o, d, interpolated=a.interpolated, threads=a.threads)
    with tempfile.TemporaryDirectory() as tmp:
        rays = os.path.join(tmp, "rays.npy")
        out = os.path.join(tmp, "hits.npy")
        out_nosites = os.path.join(tmp, "hits-no-sites.npy")
        out_hitt = os.path.join(tmp, "hits-hit-t.npy")
        floor_out = os.path.join(tmp, "floor.bin")
        answer_bytes = bytes(a.rays * 12 * 4)
        np.save(rays, np.hstack([o, d]))
        base = [a.query, a.field, "-i", rays, "-j", str(a.threads), *extra]
        c = f.center
        one_ray = [a.query, a.field, "--ray", *(str(v) for v in (c[0], c[1], c[2] + 3 * f.radius, 0, 0, -1)),
                   "-j", str(a.threads), *extra]
        cmd = base + ["-o", out]
        def fresh(*paths):
            # Each timed run writes a new file, as the I/O floor does: the previous run's answers
            # are removed first, outside the timed part (replacing a file also frees the old one's
            # pages, a cost of the previous run, not of answering rays).
            for path in paths:
                if os.path.exists(path):
                    os.remove(path)
            os.sync()

        for _ in range(a.repeat):
            # os.sync() after each run that writes a file, outside the timed parts: the kernel then
            # writes the dirty pages back now, not in the background during the next measurement
            # (on a machine of few cores that stole a share of the next path's time).
            fresh(out)
            r = subprocess.run(cmd + ["--timing"], capture_output=True, text=True, check=True)
            m = re.search(r"batch, answers kept, warm: [0-9.]+ s \(([0-9.]+) Mrays/s\)", r.stderr)
            best["cpp"] = max(best["cpp"], float(m.group(1)))
            m = re.search(r"batch alone, warm: [0-9.]+ s \(([0-9.]+) Mrays/s\)", r.stderr)
            best["dropped"] = max(best["dropped"], float(m.group(1)))
            fresh(out)
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True)
            best["cli"] = max(best["cli"], a.rays / 1e6 / (time.perf_counter() - t0))
            fresh(out_nosites)
            t0 = time.perf_counter()
            subprocess.run(base + ["--no-sites", "-o", out_nosites], check=True)
            best["nosites"] = max(best["nosites"], a.rays / 1e6 / (time.perf_counter() - t0))
            fresh(out_hitt)
            t0 = time.perf_counter()
            subprocess.run(base + ["--columns", "hit,t", "-o", out_hitt], check=True)
            best["hitt"] = max(best["hitt"], a.rays / 1e6 / (time.perf_counter() - t0))
            os.sync()
            # The floor under vff-query's I/O: read the rays file and write as many bytes as its
            # answers (12 float32 columns), through the page cache, and nothing else.
            t0 = time.perf_counter()
            with open(rays, "rb") as fin:
                fin.read()
            with open(floor_out, "wb") as fout:
                fout.write(answer_bytes)
            best["floor"] = max(best["floor"], a.rays / 1e6 / (time.perf_counter() - t0))
            os.remove(floor_out)
            os.sync()
            # vff-query's fixed cost: the same command answering one ray given on the command line
            # (process start, opening the field and verifying its checksums, one answer printed).
            t0 = time.perf_counter()
            subprocess.run(one_ray, check=True, stdout=subprocess.DEVNULL)
            best["one"] = min(best["one"], time.perf_counter() - t0)
            # Warm, as the C++ batch is measured: one call untimed first, so that the field is back
            # in the caches the subprocesses above went through.
            q.intersect(o, d, interpolated=a.interpolated, threads=a.threads, out=reuse)
            t0 = time.perf_counter()
            h = q.intersect(o, d, interpolated=a.interpolated, threads=a.threads)
            best["py"] = max(best["py"], a.rays / 1e6 / (time.perf_counter() - t0))
            t0 = time.perf_counter()
            q.intersect(o, d, interpolated=a.interpolated, threads=a.threads, out=reuse)
            best["reuse"] = max(best["reuse"], a.rays / 1e6 / (time.perf_counter() - t0))
            t0 = time.perf_counter()
            q.occluded(o, d, interpolated=a.interpolated, threads=a.threads)
            best["occ"] = max(best["occ"], a.rays / 1e6 / (time.perf_counter() - t0))
        got = np.load(out)
        assert np.array_equal(got[:, 1], h.t), "vff-query and the Python batch disagree"
        assert np.array_equal(np.load(out_nosites), got[:, :9], equal_nan=True), "--no-sites changes the answers"
        assert np.array_equal(np.load(out_hitt), got[:, :2]), "--columns hit,t changes the answers"
    print("cpu: %s, %d threads, batch kernel %s" % (cpu_name(), a.threads, vff.batch_kernel()))
    print("field: %s (%d maps of %dx%d), %d ao rays, %s, best of %d" % (
        os.path.basename(a.field), f.map_count, f.map_resolution, f.map_resolution, a.rays,
        "interpolated" if a.interpolated else "nearest", a.repeat))
    print("| path | Mrays/s | x C++ batch |")
    print("|---|---:|---:|")
    print("| C++ batch (FieldQuery::intersect, answers kept in an array, warm, vff-query --timing) | %.1f | 1.00 |" % best["cpp"])
    print("| C++ batch calls alone, each chunk's answers dropped (a bound, not a use) | %.1f | %.2f |" % (
        best["dropped"], best["dropped"] / best["cpp"]))
    print("| vff-query, .npy in and out, end to end | %.1f | %.2f |" % (best["cli"], best["cli"] / best["cpp"]))
    print("| vff-query --no-sites, .npy in and out, end to end | %.1f | %.2f |" % (
        best["nosites"], best["nosites"] / best["cpp"]))
    print("| vff-query --columns hit,t, .npy in and out, end to end | %.1f | %.2f |" % (
        best["hitt"], best["hitt"] / best["cpp"]))
    print("| I/O floor: read the rays .npy, write the answers' bytes (no query) | %.1f | %.2f |" % (
        best["floor"], best["floor"] / best["cpp"]))
    # A vff-query that did nothing but its fixed cost, the I/O floor and the C++ batch, one after
    # another (each part's best time from this run).
    bound = a.rays / 1e6 / (best["one"] + a.rays / 1e6 / best["floor"] + a.rays / 1e6 / best["cpp"])
    print("| bound for vff-query: its one-ray run (%.1f ms: process start, field opened and verified), "
          "the I/O floor and the C++ batch, one after another | %.1f | %.2f |" % (
              1e3 * best["one"], bound, bound / best["cpp"]))
    print("| Python FieldQuery.intersect, numpy in and out | %.1f | %.2f |" % (best["py"], best["py"] / best["cpp"]))
    print("| Python FieldQuery.intersect, out= (arrays reused) | %.1f | %.2f |" % (best["reuse"], best["reuse"] / best["cpp"]))
    print("| Python FieldQuery.occluded (a byte per ray out; no C++ baseline here) | %.1f | - |" % best["occ"])
    print("ratio: the path's Mrays/s over the C++ batch's, same rays and field, best of %d each, "
          "taken alternately in this run" % a.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
