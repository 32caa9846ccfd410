#!/usr/bin/env python3
"""benchmarks/report.py - the results files of benchmarks/run.sh, and the READMEs' tables.

  python3 benchmarks/report.py compose RAWDIR OUT.md   the results file from run.sh's raw outputs
  python3 benchmarks/report.py readme [--check] [README.md [benchmarks/README.md]]
                                                       both READMEs' figures from benchmarks/results/
  python3 benchmarks/report.py check RESULTS.md        parses a results file back: every step there
  python3 benchmarks/report.py cpu                     this machine's CPU, as the results name it
  python3 benchmarks/report.py slug MACHINE.txt        a results file's name: <cpu>-<date>

A results file holds the machine, a summary in rounded tables, and the full output of every
benchmark command in fenced blocks; `readme` reads those blocks back with the same parsers, so every
figure in README.md and benchmarks/README.md comes from a committed results file. `readme` writes
README.md's headline table (a few rows from the newest results file) and benchmarks/README.md's full
tables, each between its file's markers; `readme --check` exits 1 when either block differs from
what the results files give (the benchmarks test runs it). Links in a block are relative to the
file's place in the source tree (README.md at the top, the full tables in benchmarks/), whatever
path is given, so a copy elsewhere checks the same.

Exit codes: 0 ok, 1 usage or a README out of date, 2 a file cannot be read or written, 3 a results
file or an output that does not parse.
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BEGIN = "<!-- benchmarks:begin: made by `python3 benchmarks/report.py readme`; do not edit -->"
END = "<!-- benchmarks:end -->"
STEPS = ["bake", "query", "accuracy-ao", "accuracy-intra-ao", "accuracy-shadows", "accuracy-reflections",
         "scene", "triangles", "compression", "sdf", "gpu", "webgpu", "python", "library", "three"]
# Steps a results file may lack: the GPU bench (no headless OpenGL), the Python module (not built),
# the distance field and the library bake (files from before they existed), the three.js frame time
# and the WebGPU query (no node, web/node_modules or chromium; no WebGPU adapter).
OPTIONAL = ("gpu", "webgpu", "python", "sdf", "library", "three")
# run.sh --only NAME: the steps it runs.
ONLY = {"bake": ["bake"], "query": ["query"], "accuracy": [s for s in STEPS if s.startswith("accuracy-")],
        "scene": ["scene"], "triangles": ["triangles"], "compression": ["compression"], "gpu": ["gpu"],
        "sdf": ["sdf"], "python": ["python"], "library": ["library"], "three": ["three"], "webgpu": ["webgpu"]}


class ParseError(Exception):
    pass


def cpu_name():
    """'model name (family F, model M)' from /proc/cpuinfo, as vff-experiments bench prints it."""
    name = family = model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                key, _, value = line.partition(":")
                key, value = key.strip(), value.strip()
                if key == "model name" and not name:
                    name = value
                elif key == "cpu family" and not family:
                    family = value
                elif key == "model" and not model:
                    model = value
    except OSError:
        pass
    if not name:
        return "unknown CPU"
    return f"{name} (family {family}, model {model})" if family else name


def slug(machine):
    s = re.sub(r"[^a-z0-9]+", "-", machine["cpu"].lower().replace("family ", "f").replace("model ", "m"))
    return f"{s.strip('-')}-{machine['date']}"


# ---- parsers of each command's output --------------------------------------------------------

def number(s):
    return float(s.strip().rstrip("%x"))


def md_rows(text):
    """The data rows of the Markdown tables in text, as lists of stripped cells."""
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("|") and not re.match(r"^\|[-:| ]+\|$", line):
            rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def md_tables(text):
    """The Markdown tables in text, each a list of rows (header first) of stripped cells."""
    tables, current = [], []
    for line in text.splitlines() + [""]:
        if line.strip().startswith("|"):
            current.append(line)
        elif current:
            tables.append(md_rows("\n".join(current)))
            current = []
    return tables


def parse_bake(text):
    m = {k: re.search(p, text) for k, p in {
        "raw": r"embree raw\s+([\d.]+) s\s+([\d.]+) Mrays/s",
        "bake": r"\nbake\s+([\d.]+) s\s+([\d.]+) Mrays/s",
        "ratio": r"ratio\s+([\d.]+)",
        "peak": r"peak memory\s+([\d.]+) MiB",
    }.items()}
    if not all(m.values()):
        raise ParseError("vff-bake --benchmark output lacks " + ", ".join(k for k, v in m.items() if not v))
    rays = re.search(r"([\d,]+|[\d.e+]+) rays", text)
    return {"raw": float(m["raw"].group(2)), "bake": float(m["bake"].group(2)), "bake_s": float(m["bake"].group(1)),
            "ratio": float(m["ratio"].group(1)), "peak": float(m["peak"].group(1)),
            "rays": rays.group(1) if rays else "-"}


def parse_query(text):
    head = re.search(r"^Query benchmark: .*?, (\d+) threads, .*?batch kernel (\S+),", text, re.M)
    if not head:
        raise ParseError("vff-experiments bench output lacks its header line")
    sets = {}
    for r in md_rows(text):
        if len(r) < 7 or r[0] == "ray set":
            continue
        key = re.match(r"\((\w+)\)", r[1])
        if key:
            sets.setdefault(r[0], {})[key.group(1)] = {"mrays": number(r[2]), "x": number(r[3]), "floor": r[6]}
    for name, q in sets.items():
        for k in ("a", "b", "d", "m"):
            if k not in q:
                raise ParseError(f"vff-experiments bench output lacks row ({k}) of ray set {name}")
    if not sets:
        raise ParseError("vff-experiments bench output has no table")
    return {"threads": int(head.group(1)), "kernel": head.group(2), "sets": sets}


RANGE = re.compile(r"^(.*) @ ([\d.]+) R$")


def parse_accuracy(text):
    """The rows of an image experiment's table: 6 columns, or 8 with the contact region's RMS and
    the rest's (ao); a configuration ending in " @ X R" names the AO range of its pass."""
    rows = []
    for r in md_rows(text):
        if len(r) not in (6, 8) or r[0] == "configuration":
            continue
        contact = len(r) == 8
        ranged = RANGE.match(r[0])
        rows.append({"config": r[0], "reconstruction": r[1], "mib": number(r[2]),
                     "rms": None if r[3].startswith("(") else number(r[3]), "time": number(r[-1]),
                     "contact": number(r[4]) if contact and r[4] not in ("-", "(reference)") else None,
                     "outside": number(r[5]) if contact and r[5] not in ("-", "(reference)") else None,
                     "base": ranged.group(1) if ranged else r[0],
                     "range": float(ranged.group(2)) if ranged else None})
    if not rows or not rows[0]["config"].startswith("exact"):
        raise ParseError("experiment output has no table starting with the exact row")
    return rows


CODEC_ROW = re.compile(r"^\s+(.+?)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)(?:\s\s(.*))?$")


def parse_compression(text):
    payload = re.search(r"distance payload (.+)$", text, re.M)
    rows = []
    for line in text.splitlines():
        m = CODEC_ROW.match(line)
        if m and "none" not in line.split()[-1:]:
            rows.append({"codec": m.group(1), "bytes": int(m.group(2)), "ratio": float(m.group(3)),
                         "vs_zstd": float(m.group(4)), "compress": float(m.group(5)),
                         "decompress": float(m.group(6)), "note": (m.group(7) or "").strip()})
    if not rows or not payload:
        raise ParseError("vff-compress --benchmark output has no codec table")
    return {"payload": payload.group(1).strip(), "rows": rows}


def parse_gpu(text):
    """The renderer, and per query the rays/s of the largest ray count with the AO image's RMS."""
    gpu = re.search(r"GL_RENDERER: (.*)\)$", text, re.M)
    queries_text, _, render_text = text.partition("ground AO")
    queries = {}
    for line in queries_text.splitlines():
        m = re.match(r"^\| 2\^(\d+) \| ([^|]+?) \| ([\d.e+]+) \| ([\d.e+]+) \| ([\d.]+) \|.*?(\d+)\)?$", line)
        if m and int(m.group(1)) >= queries.get(m.group(2), {}).get("log2", -1):
            queries[m.group(2)] = {"log2": int(m.group(1)), "gpu": float(m.group(3)), "cpu": float(m.group(4)),
                                   "ratio": float(m.group(5)), "differing": int(m.group(6))}
    for r in md_rows(render_text):
        if len(r) == 6 and r[0] in queries:
            queries[r[0]]["rms"] = r[5]
    if not gpu or not queries or any("rms" not in q for q in queries.values()):
        raise ParseError("vff-gpu-bench output lacks its GL_RENDERER, its queries or its AO table")
    result = {"gpu": gpu.group(1), "queries": queries}
    # --api vulkan, vulkan-hlsl: the same queries through the Vulkan pipeline, its device named, with
    # the kernel from the GLSL ("vulkan") and from the HLSL generated from it ("vulkan_hlsl").
    heads = list(re.finditer(r"^Vulkan: (.*?); field queries/s through .*?\(kernel from (GLSL|HLSL)\)", text, re.M))
    for i, vk in enumerate(heads):
        rates = {}
        section = text[vk.end():heads[i + 1].start() if i + 1 < len(heads) else len(text)]
        for line in section.splitlines():
            m = re.match(r"^\| 2\^(\d+) \| ([^|]+?) \| ([\d.e+]+) \| (\d+) \|$", line)
            if m and m.group(2) in queries and int(m.group(1)) >= rates.get(m.group(2), {}).get("log2", -1):
                rates[m.group(2)] = {"log2": int(m.group(1)), "rate": float(m.group(3)), "differing": int(m.group(4))}
        if not rates:
            raise ParseError(f"vff-gpu-bench --api vulkan output lacks its Vulkan table ({vk.group(2)})")
        result["vulkan" if vk.group(2) == "GLSL" else "vulkan_hlsl"] = {"device": vk.group(1), "queries": rates}
    # --sdf: the field's GLSL and a distance field's GLSL at equal memory, against the exact AO image.
    _, found, sdf_text = text.partition("at equal memory; max and RMS against the exact image")
    if found:
        m = re.match(r" \(Embree\) on the 8-bit scale; CPU: the same image by the same method on (\d+) thread", sdf_text)
        head = re.search(r"ground AO (\d+)x\d+, (\d+) rays/px, tmax 2 R, $", text[:len(text) - len(sdf_text) - len(found)])
        rows = [r for r in md_rows(sdf_text) if len(r) == 6 and r[0] != "AO by"]
        if not m or not head or len(rows) < 4:
            raise ParseError("vff-gpu-bench --sdf output lacks its equal-memory AO table")
        result["sdf"] = {"threads": int(m.group(1)), "size": int(head.group(1)), "spp": int(head.group(2)),
                         "rows": [{"by": r[0], "memory": r[1], "gpu": r[2], "cpu": float(r[3]), "max": float(r[4]),
                                   "rms": float(r[5])} for r in rows]}
    return result


def parse_scene(text):
    tables = md_tables(text)
    rows = tables[0] if tables else []
    if len(rows) < 2 or rows[0][0] != "instances":
        raise ParseError("no scene-bench table")
    m = re.search(r"(\d+) AO rays per frame.*?(\d+) frames(?: \(rays best of (\d+)\))?, (\d+) threads", text)
    if not m:
        raise ParseError("no 'N AO rays per frame ... F frames, T threads' line")
    out = {"rays": int(m.group(1)), "frames": int(m.group(2)), "best_of": int(m.group(3) or 1),
           "threads": int(m.group(4)), "rows": []}
    for r in rows[1:]:
        row = {"instances": int(r[0]), "exact": number(r[1]) + number(r[2]),
               "scene": number(r[3]) + number(r[4]), "hybrid": number(r[5]) + number(r[6]),
               "ab": number(r[7]), "ac": number(r[8]), "agree": number(r[9])}
        if len(r) >= 14:  # (b)'s floor: its rays time, and the field's answers alone on its pairs
            row.update({"scene_rays": number(r[4]), "pairs": number(r[11]), "answers": number(r[12])})
        out["rows"].append(row)
    # The ray forms (Embree's triangles and the hybrid as single rays, packets, streams) and the
    # two-pass hybrid, where the run printed them.
    for t in tables[1:]:
        if t and t[0][:3] == ["instances", "rays", "form"]:
            out["forms"] = [{"instances": int(r[0]), "rays": r[1], "form": r[2], "embree": number(r[3]) if r[3] != "-" else None,
                             "hybrid": number(r[4]), "ratio": number(r[5]), "per_call": r[6]} for r in t[1:]]
        elif t and t[0][:3] == ["instances", "rays", "vff::Scene speed-up"]:
            out["twopass"] = [{"instances": int(r[0]), "rays": r[1], "scene": number(r[2]), "twopass": number(r[3]),
                               "kept": number(r[4]),
                               "ground": number(r[8]) if len(r) >= 9 else None,
                               "total": number(r[7]) if len(r) >= 9 else None} for r in t[1:]]
    return out


def parse_triangles(text):
    rows = md_rows(text)
    if len(rows) < 2 or rows[0][0] != "triangles":
        raise ParseError("no triangle-bench table")
    m = re.search(r"(\d+) threads", text)
    out = {"threads": int(m.group(1)) if m else 0, "rows": [], "summary": []}
    for r in rows[1:]:
        out["rows"].append({"triangles": int(r[0]), "build": number(r[1]), "bake": number(r[2]),
                            "surface": (number(r[3]), number(r[4]), number(r[5])),
                            "aimed": (number(r[6]), number(r[7]), number(r[8]))})
    out["summary"] = [l.strip() for l in text.splitlines() if l.startswith(("surface rays:", "aimed rays:", "tiles, packets"))]
    for r, row in zip(rows[1:], out["rows"]):
        if len(r) >= 14:  # the tiles set in packets of 16: Embree's triangles and the hybrid
            row["tiles"] = (number(r[11]), number(r[12]), number(r[13]))
    return out


def parse_python(text):
    """benchmarks/python_query.py: the threads and rays, and each path's Mrays/s and ratio."""
    head = re.search(r"^cpu: .*, (\d+) threads, batch kernel (\w+)$", text, re.M)
    rays = re.search(r"^field: .*?, (\d+) ao rays, (\w+), best of (\d+)$", text, re.M)
    rows = [r for r in md_rows(text) if len(r) == 3 and r[0] != "path"]
    if not head or not rays or not rows or not rows[0][0].startswith("C++ batch"):
        raise ParseError("python_query.py output lacks its cpu and field lines or its table")
    return {"threads": int(head.group(1)), "kernel": head.group(2), "rays": int(rays.group(1)),
            "reconstruction": rays.group(2), "repeat": int(rays.group(3)),
            "rows": [{"path": r[0], "mrays": number(r[1]), "ratio": None if r[2] == "-" else number(r[2])}
                     for r in rows]}


def parse_library(text):
    """benchmarks/library.sh: its table of runs, and the up-to-date re-run's time."""
    rows = [r for r in md_rows(text) if r and r[0] != "run"]
    m = re.search(r"^up-to-date re-run of (\d+) entries: ([0-9.]+) s", text, re.M)
    if not rows or not m:
        raise ParseError("no library table or re-run time")
    return {"rows": rows, "entries": int(m.group(1)), "rerun": float(m.group(2))}


def library_table(lib):
    lines = ["| run | seconds | Mrays/s | / one after another |", "|---|---:|---:|---:|"]
    lines += ["| " + " | ".join(r) + " |" for r in lib["rows"]]
    return lines + ["", f"Up-to-date re-run of {lib['entries']} entries: {lib['rerun']:.2f} s."]


def parse_sdf(text):
    """vff-experiments sdf-bench: a row per mesh, field configuration and ray set."""
    head = re.search(r"^Distance-field benchmark: (\d+) rays per set, (\d+) threads, best of (\d+), .*?"
                     r"distance field (\w+), (.*)$", text, re.M)
    if not head:
        raise ParseError("vff-experiments sdf-bench output lacks its header line")
    rows, refined = [], []
    for r in md_rows(text):
        if len(r) == 12 and r[0] != "mesh":  # the refined field's table
            fit = not r[3].startswith("does not fit")
            refined.append({"mesh": r[0], "mib": number(r[1]), "set": r[2], "field": r[3] if fit else "",
                            "parts": r[4] if fit else "", "unsure": number(r[5]) if fit else 0,
                            "rate": number(r[6]) if fit else 0, "sdfrate": number(r[7]) if fit else 0,
                            "speed": number(r[8]) if fit else 0, "wrong": number(r[9]) if fit else 0,
                            "sdfwrong": number(r[10]) if fit else 0, "fits": fit, "note": r[3] if not fit else ""})
            continue
        if len(r) != 11 or r[0] == "mesh":
            continue
        voxel = re.match(r"voxel ([\d.e+-]+) R", r[3])
        rows.append({"mesh": r[0], "field": r[1], "mib": number(r[2]), "voxel": float(voxel.group(1)) if voxel else 0,
                     "set": r[4], "embree": number(r[5]), "fieldrate": number(r[6]), "sdfrate": number(r[7]),
                     "speed": number(r[8]), "fieldwrong": number(r[9]), "sdfwrong": number(r[10])})
    if not rows:
        raise ParseError("vff-experiments sdf-bench output has no table")
    return {"rays": int(head.group(1)), "threads": int(head.group(2)), "values": head.group(4), "rows": rows,
            "refined": refined}


def parse_three(text):
    """web/tools/bench-three.mjs: the renderer, the frame, and ms per frame of each effect."""
    head = re.search(r"^three\.js frame time: (.*)$", text, re.M)
    frame = re.search(r"^frame: (\d+)x(\d+), (\d+) AO rays and (\d+) shadow rays per pixel, (\d+) moving instances, "
                      r"median of (\d+) frames$", text, re.M)
    ratio = re.search(r"^field speed-up over exact \(exact ms / field ms\): ([0-9.]+)x$", text, re.M)
    rows = [r for r in md_rows(text) if len(r) == 3 and r[0] != "effect"]
    if not head or not frame or not ratio or len(rows) < 2:
        raise ParseError("bench-three.mjs output lacks its renderer, frame or ratio line or its table")
    return {"renderer": head.group(1), "width": int(frame.group(1)), "height": int(frame.group(2)),
            "ao": int(frame.group(3)), "shadow": int(frame.group(4)), "instances": int(frame.group(5)),
            "frames": int(frame.group(6)), "ratio": float(ratio.group(1)),
            "rows": [{"effect": r[0], "ms": number(r[1]), "x": number(r[2])} for r in rows]}


def parse_webgpu(text):
    """web/tools/bench-webgpu.mjs: the adapter and each query's rays per second."""
    head = re.search(r"^WebGPU: (.*?); field queries/s through the WGSL kernel \((.*?)\)", text, re.M)
    rows = []
    for line in text.splitlines():
        m = re.match(r"^\| 2\^(\d+) \| ([^|]+?) \| ([\d.e+]+) \| ([\d.]+) \|$", line)
        if m:
            rows.append({"log2": int(m.group(1)), "query": m.group(2), "rate": float(m.group(3)), "check": float(m.group(4))})
    if not head or not rows:
        raise ParseError("bench-webgpu.mjs output lacks its adapter line or its table")
    return {"adapter": head.group(1), "kernel": head.group(2), "rows": rows}


def webgpu_table(w):
    lines = ["| query | rays | WebGPU, Mrays/s | hit share or mean visibility |", "|---|---:|---:|---:|"]
    lines += [f"| {r['query']} | 2^{r['log2']} | {rate(r['rate'] / 1e6)} | {r['check']:.4f} |" for r in w["rows"]]
    return lines


def three_table(t):
    lines = ["| effect | ms/frame | / field |", "|---|---:|---:|"]
    lines += [f"| {r['effect']} | {fmt(r['ms'], 1)} | {r['x']:.2f} |" for r in t["rows"]]
    return lines + ["", f"The field's speed-up over the exact reference (exact ms / field ms): {t['ratio']:.2f}x."]


def three_heading(t):
    return (f"three.js frame time: the field effect against three-mesh-bvh's exact AO ({t['renderer']}; "
            f"{t['width']}x{t['height']}, {t['ao']} AO and {t['shadow']} shadow rays per pixel, "
            f"{t['instances']} moving instances)")


PARSERS = {"three": parse_three, "webgpu": parse_webgpu, "sdf": parse_sdf, "library": parse_library, "bake": parse_bake, "scene": parse_scene, "triangles": parse_triangles, "query": parse_query,
           "compression": parse_compression, "gpu": parse_gpu, "python": parse_python}


def parse_step(name, text):
    return (PARSERS.get(name) or parse_accuracy)(text)


# ---- the summary tables ----------------------------------------------------------------------

def fmt(v, digits=0):
    return f"{v:,.{digits}f}"


def rate(v):
    """Mrays/s or MB/s, rounded to what the run-to-run noise leaves meaningful."""
    return fmt(v, 1 if v < 10 else 0)


def bake_table(m, b):
    return [f"| mesh | field | Embree alone, Mrays/s | whole bake, Mrays/s | bake / Embree | peak memory |",
            "|---|---|---:|---:|---:|---:|",
            f"| {m['mesh']} | {m['field']} | {rate(b['raw'])} | {rate(b['bake'])} | {b['ratio']:.2f} | "
            f"{fmt(b['peak'])} MiB |"]


def query_rows(m, q, with_cpu):
    out = []
    for name, s in q["sets"].items():
        cells = ([f"{m['cpu']}, {m['cores']} cores"] if with_cpu else []) + [
            name, rate(s["a"]["mrays"]), rate(s["b"]["mrays"]), f"{s['b']['x']:.1f}x",
            rate(s["m"]["mrays"]), s["b"]["floor"], f"{s['d']['x']:.1f}x"]
        out.append("| " + " | ".join(cells) + " |")
    return out


def query_header(with_cpu):
    cols = (["CPU"] if with_cpu else []) + [
        "ray set", "Embree, Mrays/s", "field batch (b), Mrays/s", "(b) x Embree", "memory floor (m), Mrays/s",
        "(b) share of floor", "interpolated (d) x Embree"]
    return ["| " + " | ".join(cols) + " |", "|" + "---|" * (2 if with_cpu else 1) + "---:|" * (len(cols) - (2 if with_cpu else 1))]


def accuracy_table(steps, only=None):
    lines = ["| experiment | field | memory MiB | RMS nearest | RMS interpolated | time s: exact / nearest |",
             "|---|---|---:|---:|---:|---:|"]
    for name in STEPS:
        if not name.startswith("accuracy-") or name not in steps:
            continue
        rows = steps[name]
        exact = rows[0]
        configs = []
        exacts = {r["range"]: r for r in rows if r["config"].startswith("exact")}  # one per AO range
        for r in rows[1:]:
            if r["config"] not in configs and not r["config"].startswith("exact"):
                configs.append(r["config"])
        for c in configs:
            sdf = re.match(r"distance field, (\S+)'s memory", c)
            by = {r["reconstruction"]: r for r in rows if r["config"] == c}
            first_row = next(iter(by.values()))
            if only and (first_row["range"] not in (None, 2.0) or
                         (first_row["base"] != only and not (sdf and sdf.group(1) == only))):
                continue
            near, interp = by.get("nearest"), by.get("interpolated")
            if sdf:  # the distance field at that field's memory: sphere tracing, and its cone estimate
                near, interp = by.get("sphere trace"), by.get("cone")
                c = f"distance field at {sdf.group(1)}'s memory" + \
                    (f" @ {first_row['range']:g} R" if first_row["range"] is not None else "")
            first = near or interp
            exact = exacts.get(first["range"], rows[0])
            lines.append(f"| {name[len('accuracy-'):]} | {c} | {first['mib']:.1f} | "
                         f"{near['rms']:.2f} | " if near else f"| {name[len('accuracy-'):]} | {c} | {first['mib']:.1f} | - | ")
            lines[-1] += (f"{interp['rms']:.2f} | " if interp else "- | ") + \
                f"{exact['time']:.2f} / {first['time']:.2f} |"
    return lines


def contact_table(steps):
    """Ground AO by range (the ao experiment's passes): the error over the contact region (plane
    pixels inside the bounding sphere) against the rest's, and each range's whole RMS against 2 R's."""
    rows = [r for r in steps.get("accuracy-ao", []) if r["range"] is not None and r["contact"] is not None]
    if not rows:
        return []
    at2 = {(r["base"], r["reconstruction"]): r["rms"] for r in rows if r["range"] == 2.0}
    lines = ["| field | reconstruction | AO range | RMS | RMS contact | RMS outside | contact / outside "
             "(target <= 2) | RMS / RMS at 2 R (target at 0.5 R <= 1.5) |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        ratio = r["contact"] / r["outside"] if r["outside"] else float("nan")
        base = at2.get((r["base"], r["reconstruction"]))
        lines.append(f"| {r['base']} | {r['reconstruction']} | {r['range']:g} R | {r['rms']:.2f} | {r['contact']:.2f} | "
                     f"{r['outside']:.2f} | {ratio:.1f} | " + (f"{r['rms'] / base:.2f}" if base else "-") + " |")
    return lines


def sdf_table(d):
    lines = ["| mesh | memory MiB | ray set | Embree, Mrays/s | field, Mrays/s | distance field, Mrays/s | "
             "field / SDF speed | wrong answers: field / SDF | faster, more often right |",
             "|---|---:|---|---:|---:|---:|---:|---:|---|"]
    for r in d["rows"]:
        faster = "field" if r["speed"] > 1 else "SDF"
        right = "field" if r["fieldwrong"] < r["sdfwrong"] else "SDF" if r["sdfwrong"] < r["fieldwrong"] else "tie"
        lines.append(f"| {r['mesh']} | {r['mib']:.1f} | {r['set']} | {rate(r['embree'])} | {rate(r['fieldrate'])} | "
                     f"{rate(r['sdfrate'])} | {r['speed']:.1f}x | {r['fieldwrong']:.2f}% / {r['sdfwrong']:.2f}% | "
                     f"{faster}, {right} |")
    return lines


def refined_table(d):
    lines = ["| mesh | memory MiB | ray set | refined field | maps + unsure bits + exact step, MiB | unsure texels | "
             "refined, Mrays/s | distance field, Mrays/s | refined / SDF speed | wrong answers: refined / SDF | "
             "10x faster, as often right |", "|---|---:|---|---|---|---:|---:|---:|---:|---:|---|"]
    for r in d.get("refined", []):
        if not r["fits"]:
            lines.append(f"| {r['mesh']} | {r['mib']:.1f} | {r['set']} | {r['note']} | | | | | | | no |")
            continue
        ok = "yes" if r["speed"] >= 10 and r["wrong"] <= r["sdfwrong"] else "no"
        lines.append(f"| {r['mesh']} | {r['mib']:.1f} | {r['set']} | {r['field']} | {r['parts']} | {r['unsure']:.1f}% | "
                     f"{rate(r['rate'])} | {rate(r['sdfrate'])} | {r['speed']:.1f}x | "
                     f"{r['wrong']:.3f}% / {r['sdfwrong']:.3f}% | {ok} |")
    return lines


def sdf_summary(d):
    """The README's short form: a row per mesh and memory, both ray sets in each cell (ao / aimed)."""
    lines = ["| mesh | memory MiB | field / SDF speed (ao / aimed) | wrong answers, field (ao / aimed) | "
             "wrong answers, SDF (ao / aimed) |", "|---|---:|---:|---:|---:|"]
    groups = {}
    for r in d["rows"]:
        groups.setdefault((r["mesh"], r["mib"]), {})[r["set"]] = r
    for (mesh, mib), g in groups.items():
        sets = [g[k] for k in ("ao", "aimed") if k in g]
        lines.append(f"| {mesh} | {mib:.1f} | " + " / ".join(f"{r['speed']:.0f}x" for r in sets) + " | " +
                     " / ".join(f"{r['fieldwrong']:.2f}%" for r in sets) + " | " +
                     " / ".join(f"{r['sdfwrong']:.2f}%" for r in sets) + " |")
    return lines


def refined_summary(d):
    """The README's short form of the refined table: a row per mesh and memory that fits."""
    lines = ["| mesh | memory MiB | refined / SDF speed (ao / aimed) | wrong answers, refined (ao / aimed) | "
             "wrong answers, SDF (ao / aimed) |", "|---|---:|---:|---:|---:|"]
    groups = {}
    for r in d.get("refined", []):
        groups.setdefault((r["mesh"], r["mib"]), {})[r["set"]] = r
    for (mesh, mib), g in groups.items():
        sets = [g[k] for k in ("ao", "aimed") if k in g]
        if not all(r["fits"] for r in sets):
            lines.append(f"| {mesh} | {mib:.1f} | {sets[0]['note']} | | |")
            continue
        lines.append(f"| {mesh} | {mib:.1f} | " + " / ".join(f"{r['speed']:.1f}x" for r in sets) + " | " +
                     " / ".join(f"{r['wrong']:.3f}%" for r in sets) + " | " +
                     " / ".join(f"{r['sdfwrong']:.3f}%" for r in sets) + " |")
    return lines


def compression_table(c):
    lines = ["| codec | bytes / payload | bytes / zstd -19's | decompression, MB/s (1 core) |",
             "|---|---:|---:|---:|"]
    for r in c["rows"]:
        lossy = " (lossy)" if r["note"] == "lossy" else ""
        lines.append(f"| {r['codec']}{lossy} | {1 / r['ratio']:.3f} | "
                     f"{r['vs_zstd']:.2f} | {rate(r['decompress'])} |")
    return lines


def gpu_table(g):
    lines = ["| query | rays | GPU, Mrays/s | CPU, Mrays/s | GPU / CPU | answers differing | AO image RMS, GPU vs CPU |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name, q in g["queries"].items():
        lines.append(f"| {name} | 2^{q['log2']} | {rate(q['gpu'] / 1e6)} | {rate(q['cpu'] / 1e6)} | {q['ratio']:.2f} | "
                     f"{q['differing']} | {q['rms']} |")
    return lines


def gpu_vulkan_table(g, key="vulkan"):
    lines = ["| query | rays | Vulkan, Mrays/s | OpenGL, Mrays/s (at its largest count) | answers differing from the CPU |",
             "|---|---:|---:|---:|---:|"]
    for name, q in g[key]["queries"].items():
        lines.append(f"| {name} | 2^{q['log2']} | {rate(q['rate'] / 1e6)} | {rate(g['queries'][name]['gpu'] / 1e6)} | "
                     f"{q['differing']} |")
    return lines


def gpu_sdf_table(d):
    lines = ["| AO by | memory | GPU frame, s | CPU, s | RMS against exact (8-bit) | max |",
             "|---|---|---:|---:|---:|---:|"]
    for r in d["rows"]:
        lines.append(f"| {r['by']} | {r['memory']} | {r['gpu']} | {fmt(r['cpu'], 3)} | {r['rms']:.3f} | {r['max']:.0f} |")
    return lines


def scene_table(sc):
    lines = ["| moving instances | Embree instancing, ms/frame | vff::Scene, ms/frame | hybrid (Embree top level), "
             "ms/frame | vff::Scene / Embree speed-up | hybrid speed-up | answers equal to Embree's |",
             "|---:|---:|---:|---:|---:|---:|---:|"]
    for r in sc["rows"]:
        lines.append(f"| {r['instances']} | {fmt(r['exact'], 1)} | {fmt(r['scene'], 1)} | {fmt(r['hybrid'], 1)} | "
                     f"{r['ab']:.2f}x | {r['ac']:.2f}x | {100 * r['agree']:.1f}% |")
    single = next((r["ab"] for r in sc["rows"] if r["instances"] == 1), None)
    k = next((r["ab"] for r in sc["rows"] if r["instances"] == 1000), None)
    if single and k:
        lines += ["", f"At 1000 instances the field scene keeps {k / single:.2f} of the single object's speed-up "
                      f"({k:.2f}x against {single:.2f}x; target 0.8)."]
    floor = {r["instances"]: r for r in sc["rows"] if "answers" in r}
    if 1 in floor and 1000 in floor:
        f1, fk = floor[1], floor[1000]
        lines += ["", "Where vff::Scene's rays time goes: the field's batch answering exactly its (ray, instance) "
                      "pairs, found beforehand, takes "
                      f"{fmt(f1['answers'], 2)} of {fmt(f1['scene_rays'], 2)} ms a frame at 1 instance and "
                      f"{fmt(fk['answers'], 2)} of {fmt(fk['scene_rays'], 2)} ms at 1000 ({fk['pairs']:.2f} pairs a "
                      "ray); the rest is finding the pairs in the hierarchy and taking each ray into its instance's "
                      "object space."]
    return lines


def forms_table(sc):
    lines = ["| moving instances | AO rays | form | Embree triangles, Mrays/s | hybrid, Mrays/s | hybrid / Embree | "
             "active rays a callback |", "|---:|---|---|---:|---:|---:|---:|"]
    for r in sc.get("forms", []):
        lines.append(f"| {r['instances']} | {r['rays']} | {r['form']} | " + (rate(r['embree']) if r['embree'] else "-") +
                     f" | {rate(r['hybrid'])} | {r['ratio']:.2f}x | {r['per_call']} |")
    return lines


def twopass_table(sc):
    lines = ["| moving instances | AO rays | vff::Scene over Embree instancing | two-pass hybrid over Embree + ground | "
             "kept (target 0.8) | two-pass, ns/ray | of it the ground pass |", "|---:|---|---:|---:|---:|---:|---:|"]
    for r in sc.get("twopass", []):
        lines.append(f"| {r['instances']} | {r['rays']} | {r['scene']:.2f}x | {r['twopass']:.2f}x | {r['kept']:.2f} | " +
                     (f"{r['total']:.1f} | {r['ground']:.1f} |" if r.get("total") is not None else "- | - |"))
    return lines


def triangles_table(t):
    tiles = all("tiles" in r for r in t["rows"]) and t["rows"]
    lines = ["| triangles | surface AO rays: Embree, ns/ray | field, ns/ray | speed-up | aimed rays: Embree, ns/ray | "
             "field, ns/ray | speed-up |" + (" tiles, packets of 16: Embree, ns/ray | hybrid, ns/ray | hybrid speed-up |"
                                             if tiles else ""),
             "|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|---:|" if tiles else "")]
    for r in t["rows"]:
        s, a = r["surface"], r["aimed"]
        lines.append(f"| {r['triangles']} | {fmt(s[0], 1)} | {fmt(s[1], 1)} | {s[2]:.1f}x | {fmt(a[0], 1)} | "
                     f"{fmt(a[1], 1)} | {a[2]:.1f}x |" +
                     (f" {fmt(r['tiles'][0], 1)} | {fmt(r['tiles'][1], 1)} | {r['tiles'][2]:.2f}x |" if tiles else ""))
    if t["summary"]:
        lines += ["", *[f"- {l}" for l in t["summary"]]]
    return lines


def python_table(p):
    lines = ["| path | Mrays/s | x C++ batch |", "|---|---:|---:|"]
    for r in p["rows"]:
        lines.append(f"| {r['path']} | {rate(r['mrays'])} | " + ("-" if r["ratio"] is None else f"{r['ratio']:.2f}") + " |")
    return lines


def sections(machine, steps, heading, queries=None, only=None):
    """The summary's tables, one per topic; `queries` (a list of (machine, query)) replaces the
    query table of this run by one row per ray set of each CPU on record; `only` keeps the
    accuracy rows of that field configuration."""
    out = []
    if "bake" in steps:
        out += [f"{heading} Bake speed", "", *bake_table(machine, steps["bake"]), ""]
    if queries:
        out += [f"{heading} Query speed, each CPU on record (its newest results file)", "", *query_header(True)]
        for m, q in queries:
            out += query_rows(m, q, True)
        out += ["", "Threads and batch kernel: " + "; ".join(f"{m['cpu']}: {q['threads']}, {q['kernel']}"
                                                          for m, q in queries) + ".", ""]
    elif "query" in steps:
        q = steps["query"]
        out += [f"{heading} Query speed ({q['threads']} threads, {q['kernel']} kernel)", "",
                *query_header(False), *query_rows(machine, q, False), ""]
    if any(k.startswith("accuracy-") for k in steps):
        out += [f"{heading} Accuracy against exact Embree casts (8-bit scale)", "", *accuracy_table(steps, only), ""]
        if any(r["config"].startswith("distance field") for k, v in steps.items() if k.startswith("accuracy-") for r in v):
            out += ["Distance-field rows: nearest is sphere tracing's hit or miss, interpolated its cone estimate.", ""]
        if not only and contact_table(steps):
            out += [f"{heading} Contact shadows: ground AO by range (rays from the ground carry no source: "
                    "spec/geometry.md 7.4)", "", *contact_table(steps), "",
                    "Contact: the plane pixels inside the bounding sphere, whose rays start inside it; outside: the "
                    "rest of the plane.", ""]
    if "scene" in steps:
        sc = steps["scene"]
        best = f", rays best of {sc['best_of']}" if sc["best_of"] > 1 else ""
        out += [f"{heading} Scenes: time per frame against moving instances ({sc['rays']} AO rays per frame{best}, "
                f"{sc['threads']} threads)", "", *scene_table(sc), ""]
        if sc.get("forms") and not only:
            out += [f"{heading} Ray forms: Embree's triangles and the hybrid (FieldGeometry, ray sources) as a renderer "
                    "casts them", "", *forms_table(sc), "",
                    "random: AO rays from random points of the instances; tiles: a G-buffer pass's, 16 a pixel, cast "
                    "4 x 4 pixels at a time (a packet of 16 is one sample of a tile). The vff::Scene row: its batches, "
                    "and its speed-up over Embree's single rays.", "",
                    f"{heading} Two-pass hybrid: field objects and a static environment (a ground quad)", "",
                    *twopass_table(sc), ""]
    if "triangles" in steps:
        t = steps["triangles"]
        out += [f"{heading} Time per ray against the object's triangle count ({t['threads']} threads)", "",
                *triangles_table(t), ""]
    if "compression" in steps:
        c = steps["compression"]
        out += [f"{heading} Compression of the distance payload ({c['payload']})", "", *compression_table(c), ""]
    if "sdf" in steps:
        d = steps["sdf"]
        out += [f"{heading} Field against a signed distance field at equal memory per object ({d['values']} values, "
                f"{d['threads']} threads, {d['rays']} rays per set)", "", *sdf_table(d), "",
                "Wrong answers: rays answered otherwise than Embree (occluded or not); field / SDF speed above 1x: the "
                "field is faster.", ""]
        if d.get("refined"):
            out += [f"{heading} Refined field against the distance field at the distance field's memory", "",
                    *refined_table(d), "",
                    "Refined: the maps answer the rays they are sure of, an exact ray cast through the object's "
                    "triangles the rest (vff/refine.h); its memory counts the maps, one unsure bit a texel, the "
                    "vertex positions and the triangle BVH.", ""]
    if "gpu" in steps:
        renderer = steps["gpu"]["gpu"]
        soft = ": Mesa's software rasteriser, on the CPU" if "llvmpipe" in renderer else ""
        out += [f"{heading} GPU query ({renderer}{soft})", "", *gpu_table(steps["gpu"]), ""]
        for key, what, how in (("vulkan", "", "The same vff_query.glsl compiled to SPIR-V (gpu/vulkan)"),
                               ("vulkan_hlsl", ", kernel from the generated HLSL",
                                "The HLSL generated from the same GLSL (spirv-cross), compiled by glslang's HLSL "
                                "front end")):
            if key not in steps["gpu"]:
                continue
            device = steps["gpu"][key]["device"]
            vsoft = ": Mesa's lavapipe, on the CPU" if "llvmpipe" in device else ""
            out += [f"{heading} GPU query through Vulkan{what} ({device}{vsoft})", "",
                    *gpu_vulkan_table(steps["gpu"], key), "",
                    f"{how}; each answer carries both reconstructions and the lookup, 80 bytes a ray.", ""]
        if "sdf" in steps["gpu"]:
            d = steps["gpu"]["sdf"]
            out += [f"{heading} GPU ground AO, field against a distance field at equal memory ({renderer}{soft}; "
                    f"{d['size']}x{d['size']}, {d['spp']} rays/px; CPU baseline on {d['threads']} threads)", "",
                    *gpu_sdf_table(d), ""]
    if "webgpu" in steps:
        w = steps["webgpu"]
        wsoft = ": SwiftShader, on the CPU" if "swiftshader" in w["adapter"].lower() else ""
        out += [f"{heading} GPU query through WebGPU ({w['adapter']}{wsoft})", "", *webgpu_table(w), "",
                f"The WGSL generated from the same GLSL ({w['kernel']}) in headless Chromium, on ground-AO "
                "rays; each answer carries both reconstructions and the lookup, 80 bytes a ray.", ""]
    if "python" in steps:
        p = steps["python"]
        out += [f"{heading} Python and vff-query against the C++ batch ({p['rays']} ao rays, {p['reconstruction']}, "
                f"{p['threads']} threads)", "", *python_table(p), "",
                "Each ratio: the path's rate over the first row's (the C++ batch, FieldQuery::intersect on the same "
                "rays and field, warm), each the best of its runs, taken alternately in the same run.", ""]
    if "library" in steps:
        out += [f"{heading} Library bake (vff-library against the same bakes one after another)", "",
                *library_table(steps["library"]), ""]
    if "three" in steps:
        out += [f"{heading} {three_heading(steps['three'])}", "", *three_table(steps["three"]), ""]
    return out


# ---- results files ---------------------------------------------------------------------------

def read_machine(path):
    machine = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            k, _, v = line.rstrip("\n").partition("=")
            if k:
                machine[k] = v
    for k in ("date", "commit", "cpu", "cores", "mesh", "field"):
        if k not in machine:
            raise ParseError(f"{path}: no '{k}='")
    return machine


def compose(rawdir, out):
    machine = read_machine(os.path.join(rawdir, "machine.txt"))
    steps, texts = {}, {}
    for name in STEPS:
        path = os.path.join(rawdir, name + ".txt")
        if not os.path.exists(path):
            continue
        with open(path, encoding="utf-8") as f:
            texts[name] = f.read()
        with open(os.path.join(rawdir, name + ".cmd"), encoding="utf-8") as f:
            texts[name + ".cmd"] = f.read().strip()
        try:
            steps[name] = parse_step(name, texts[name])
        except ParseError as e:
            raise ParseError(f"{path}: {e}") from None
    lines = [f"# vff benchmarks: {machine['cpu']}, {machine['date']}", "",
             "Written by `bash benchmarks/run.sh`" + (" --quick (tiny sizes: the figures mean nothing)"
                                                       if machine.get("quick") == "1" else "") +
             (f" --only {machine['only']} (a reduced run: those steps alone)" if machine.get("only") else "") + ".", "",
             "| | |", "|---|---|"]
    for k in ("commit", "cpu", "cores", "kernel", "compiler", "build_type", "embree", "mesh", "field"):
        if k in machine:
            lines.append(f"| {k} | {machine[k]} |")
    lines += ["", "## Summary", "", *sections(machine, steps, "###"), "## Full output", ""]
    for name in STEPS:
        if name in texts:
            lines += [f"### {name}", "", "`" + texts[name + ".cmd"] + "`", "", "```text", texts[name].rstrip("\n"),
                      "```", ""]
    for name in OPTIONAL:
        skip = os.path.join(rawdir, name + ".skip")
        if name not in texts and os.path.exists(skip):
            with open(skip, encoding="utf-8") as f:
                lines += [f"### {name}", "", "Not run: " + (f.read().strip() or f"the {name} step failed to start") + ".", ""]
    with open(out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def read_results(path):
    """(machine, steps) of a results file, parsed back from its full-output blocks."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    machine = {}
    head = re.search(r"^# vff benchmarks: (.*), (\d{4}-\d\d-\d\d)$", text, re.M)
    if not head:
        raise ParseError(f"{path}: no '# vff benchmarks: CPU, DATE' heading")
    machine["cpu"], machine["date"] = head.group(1), head.group(2)
    for k, v in re.findall(r"^\| (\w+) \| (.*) \|$", text, re.M):
        machine.setdefault(k, v)
    machine["quick"] = "1" if "--quick" in text.split("## Summary")[0] else "0"
    only = re.search(r"--only ([\w,]+) \(a reduced run", text.split("## Summary")[0])
    if only:
        machine["only"] = only.group(1)
    steps = {}
    for name, cmd, body in re.findall(r"^### ([\w-]+)\n\n`([^\n]*)`\n\n```text\n(.*?)\n```$", text, re.M | re.S):
        try:
            steps[name] = parse_step(name, body)
            if name == "sdf":
                steps["sdf_cmd"] = cmd
        except ParseError as e:
            raise ParseError(f"{path}, {name}: {e}") from None
    return machine, steps


def load_runs(results_dir):
    """The results files that are not --quick, oldest first, as (path, machine, steps); and the
    newest whole run (not --only) among them."""
    runs = [(p, *read_results(p)) for p in sorted(glob.glob(os.path.join(results_dir, "*.md")))]
    runs = sorted((r for r in runs if r[1].get("quick") != "1"), key=lambda r: (r[1]["date"], r[0]))
    if not runs:
        raise ParseError(f"{results_dir}: no results file")
    full = [r for r in runs if not r[1].get("only")]
    if not full:
        raise ParseError(f"{results_dir}: no results file of a whole run")
    return runs, full[-1]


def link(path, base):
    """A Markdown link to path, relative to the folder base (the file's folder in the source tree)."""
    return f"[{os.path.relpath(path, ROOT)}]({os.path.relpath(path, base)})"


def full_block(runs, newest, base):
    """benchmarks/README.md's block: every summary table of the newest whole run, the query table
    with a row for each CPU on record, and the distance-field comparison of the newest file that
    has it."""
    path, machine, steps = newest
    latest = {m["cpu"]: (m, s["query"]) for _, m, s in runs if "query" in s}
    lines = [BEGIN, "",
             f"From {link(path, base)}: {machine['cpu']}, {machine['cores']} cores, commit {machine['commit']}, "
             f"{machine['mesh']}, field {machine['field']}; the query table has a row for each CPU on record. "
             "Figures differ between CPUs: `bash benchmarks/run.sh` measures yours.", ""]
    main = sections(machine, {k: v for k, v in steps.items() if k not in ("sdf", "three", "webgpu", "gpu")}, "###",
                    list(latest.values()), machine["field"])
    # The GPU tables, the distance-field comparison, the WebGPU query and the three.js frame time: each
    # from the newest file that has it (a whole run, or --only gpu / sdf / webgpu / three).
    gsteps, source = newest_with(runs, "gpu", base)
    if gsteps:
        main += ["### GPU query and ground AO: OpenGL, and Vulkan with GLSL and HLSL kernels", "", f"{source}.", "",
                 *sections(machine, {"gpu": gsteps["gpu"]}, "####")]
    ssteps, source = newest_with(runs, "sdf", base)
    if ssteps:
        d = ssteps["sdf"]
        main += [f"### Field against a signed distance field at equal memory per object", "",
                 f"{source}, {d['values']} values, {d['rays']} rays per set; command "
                 f"`{ssteps['sdf_cmd']}`. Speed above 1x: the field is faster; wrong answers: rays answered otherwise "
                 "than Embree.", "", *sdf_summary(d), ""]
        if d.get("refined"):
            main += ["The refined field (`vff-bake --refine`, `Reconstruction::kRefined`) at the distance field's "
                     "memory (its maps, unsure bits and exact step together), from the same run:", "",
                     *refined_summary(d), ""]
    wsteps, source = newest_with(runs, "webgpu", base)
    if wsteps:
        w = wsteps["webgpu"]
        main += [f"### GPU query through WebGPU ({w['adapter']})", "",
                 f"{source}; the WGSL generated from the GLSL query ({w['kernel']}) in headless Chromium, on "
                 "ground-AO rays; each answer carries both reconstructions and the lookup, 80 bytes a ray.", "",
                 *webgpu_table(w), ""]
    tsteps, source = newest_with(runs, "three", base)
    if tsteps:
        t = tsteps["three"]
        main += [f"### {three_heading(t)}", "",
                 f"{source}; the example scene (web/examples/contact-shadows), the same page, frame and "
                 f"rays for each effect, median of {t['frames']} frames.", "", *three_table(t), ""]
    return "\n".join(lines + main + [END])


def newest_with(runs, step, base):
    """The steps of the newest run that has `step`, and the words naming it ("From <file> (a reduced
    run): CPU, cores, commit"); (None, None) when no run has it."""
    have = [r for r in runs if step in r[2]]
    if not have:
        return None, None
    path, machine, steps = have[-1]
    reduced = f" (`run.sh --only {machine['only']}`: a reduced run)" if machine.get("only") else ""
    return steps, f"From {link(path, base)}{reduced}: {machine['cpu']}, {machine['cores']} cores, commit {machine['commit']}"


def sdf_headline_row(machine, d):
    """The distance-field row the headline quotes: the ao rays on the run's own mesh (else the first)
    at the run's field configuration (else the largest memory)."""
    rows = [r for r in d["rows"] if r["set"] == "ao"] or d["rows"]
    mine = [r for r in rows if r["mesh"] == machine.get("mesh")] or [r for r in rows if r["mesh"] == rows[0]["mesh"]]
    same = [r for r in mine if r["field"] == machine.get("field")]
    return same[0] if same else max(mine, key=lambda r: r["mib"])


def headline_table(machine, steps, sdf):
    """README.md's one table: vff against its baseline on each topic the run has, a row each."""
    rows = []
    if "bake" in steps:
        b = steps["bake"]
        rows.append(("bake: the whole bake against Embree alone on the bake's rays, Mrays/s", rate(b["bake"]),
                     rate(b["raw"]), f"{b['ratio']:.2f}x"))
    if "query" in steps:
        sets = steps["query"]["sets"]
        name = "ao" if "ao" in sets else next(iter(sets))
        s = sets[name]
        rows.append((f"query, {name} rays: the field's batch against Embree, Mrays/s", rate(s["b"]["mrays"]),
                     rate(s["a"]["mrays"]), f"{s['b']['x']:.1f}x"))
        rows.append((f"query, {name} rays: the field's batch against the memory floor, Mrays/s",
                     rate(s["b"]["mrays"]), rate(s["m"]["mrays"]), s["b"]["floor"]))
    if "scene" in steps and steps["scene"]["rows"]:
        sc = steps["scene"]["rows"]
        r = next((r for r in sc if r["instances"] == 1000), sc[-1])
        rows.append((f"{r['instances']} moving instances: vff::Scene against Embree instancing, ms/frame",
                     fmt(r["scene"], 1), fmt(r["exact"], 1), f"{r['ab']:.2f}x"))
    if "triangles" in steps and steps["triangles"]["rows"]:
        r = max(steps["triangles"]["rows"], key=lambda r: r["triangles"])
        s = r["surface"]
        rows.append((f"an object of {r['triangles']} triangles, surface AO rays: the field against Embree, ns/ray",
                     fmt(s[1], 1), fmt(s[0], 1), f"{s[2]:.1f}x"))
    if sdf:
        r = sdf_headline_row(machine, sdf)
        rows.append((f"{r['mesh']} at {r['mib']:.1f} MiB, {r['set']} rays: the field against a signed distance "
                     "field of the same memory, Mrays/s", rate(r["fieldrate"]), rate(r["sdfrate"]),
                     f"{r['speed']:.0f}x"))
        rows.append(("the same: rays answered otherwise than Embree", f"{r['fieldwrong']:.2f}%",
                     f"{r['sdfwrong']:.2f}%", "-"))
    return ["| vff against | vff | baseline | vff's speed / baseline's |", "|---|---:|---:|---:|",
            *[f"| {a} | {v} | {b} | {x} |" for a, v, b, x in rows]]


def headline_block(runs, newest, base):
    """README.md's block: the headline table from the newest whole run (the distance-field rows
    from the newest file that has them), the CPU named, and a link to the full tables."""
    path, machine, steps = newest
    with_sdf = [r for r in runs if "sdf" in r[2]]
    sdf = with_sdf[-1] if with_sdf else None
    threads = f", {steps['query']['threads']} threads" if "query" in steps else ""
    lines = [BEGIN, "",
             f"From {link(path, base)}: {machine['cpu']}, {machine['cores']} cores{threads}, commit "
             f"{machine['commit']}, {machine['mesh']}, field {machine['field']}. Every table, each CPU on record: "
             f"{link(os.path.join(ROOT, 'benchmarks', 'README.md'), base)}.", "",
             *headline_table(machine, steps, sdf[2]["sdf"] if sdf else None)]
    if sdf and sdf[0] != path:
        lines += ["", f"Distance-field rows from {link(sdf[0], base)} ({sdf[1]['cpu']}, commit {sdf[1]['commit']})."]
    return "\n".join(lines + ["", END])


def replace_block(path, block):
    """(old text, new text) of the file at path with its block between the markers replaced."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise ParseError(f"{path}: needs one '{BEGIN}' line and one '{END}' line")
    start, end = text.index(BEGIN), text.index(END) + len(END)
    return text, text[:start] + block + text[end:]


def readme(args):
    check = "--check" in args
    args = [a for a in args if a != "--check"]
    if len(args) > 2 or any(a.startswith("-") for a in args):
        print("usage: report.py readme [--check] [README.md [benchmarks/README.md]]", file=sys.stderr)
        return 1
    paths = args + [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "benchmarks", "README.md")][len(args):]
    runs, newest = load_runs(os.path.join(ROOT, "benchmarks", "results"))
    # Each block's links are relative to its file's place in the source tree, not to the path given.
    blocks = [headline_block(runs, newest, ROOT), full_block(runs, newest, os.path.join(ROOT, "benchmarks"))]
    what = [("headline table", "differs from", "matches"), ("benchmark tables", "differ from", "match")]
    texts = [replace_block(p, b) for p, b in zip(paths, blocks)]
    if check:
        stale = [(p, w) for p, w, (old, new) in zip(paths, what, texts) if old != new]
        for p, (w, differ, _) in stale:
            print(f"report.py: {p}: its {w} {differ} benchmarks/results/ "
                  "(run python3 benchmarks/report.py readme)", file=sys.stderr)
        if stale:
            return 1
        for p, (w, _, match) in zip(paths, what):
            print(f"report.py: {p}: its {w} {match} benchmarks/results/")
        return 0
    for p, (old, new) in zip(paths, texts):
        if new != old:
            with open(p + ".tmp", "w", encoding="utf-8") as f:
                f.write(new)
            os.replace(p + ".tmp", p)
    return 0


def main(argv):
    if len(argv) >= 2 and argv[1] == "cpu":
        print(cpu_name())
        return 0
    if len(argv) == 3 and argv[1] == "slug":
        print(slug(read_machine(argv[2])))
        return 0
    if len(argv) == 4 and argv[1] == "compose":
        compose(argv[2], argv[3])
        return 0
    if len(argv) == 3 and argv[1] == "check":
        machine, steps = read_results(argv[2])
        wanted = [n for step in machine["only"].split(",") for n in ONLY.get(step, [])] if machine.get("only") else STEPS
        missing = [n for n in wanted if n not in OPTIONAL and n not in steps]
        if missing:
            raise ParseError(f"{argv[2]}: no output of " + ", ".join(missing))
        print(f"report.py: {argv[2]}: {machine['cpu']}, {machine['date']}: " + ", ".join(k for k in steps if k in STEPS))
        return 0
    if len(argv) >= 2 and argv[1] == "readme":
        return readme(argv[2:])
    print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
    return 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except ParseError as e:
        print(f"report.py: error: {e}", file=sys.stderr)
        sys.exit(3)
    except OSError as e:
        print(f"report.py: error: {e.filename}: {e.strerror}", file=sys.stderr)
        sys.exit(2)
