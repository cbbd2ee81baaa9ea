#!/usr/bin/env python3
"""The speed report's tables (scripts/report speed): the frame path's stages from `liveprobe
bench --json` files (arguments after the first: LABEL=FILE), then from liveprobe-bench's JSON
(the first argument) the projection on every SIMD path with the two floors of the same run, the
bracket merge beside the projection of the frame it makes, and the other benchmarks. Medians."""
import json
import re
import sys

UNIT = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def seconds(b):
    return b["real_time"] * UNIT[b["time_unit"]]


def fmt(s):
    if s >= 1.0:
        return f"{s:.2f} s"
    if s >= 1e-3:
        return f"{s * 1e3:.3g} ms" if s < 0.1 else f"{s * 1e3:.0f} ms"
    return f"{s * 1e6:.3g} us"


STAGES = ["grab", "convert", "project", "resample", "upload", "render", "readback"]
print("| `liveprobe bench` (headless, 640x360, the default sphere) | " + " | ".join(STAGES) + " |")
print("|---|" + "---|" * len(STAGES))
for arg in sys.argv[2:]:
    label, path = arg.split("=", 1)
    stages = json.load(open(path))["stages"]
    print(f"| {label} | " + " | ".join(f"{stages[s]['median_ms']:.2f} ms" if s in stages else ""
                                       for s in STAGES) + " |")
print()

medians = {}
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b.get("aggregate_name") == "median":
        medians[b["run_name"]] = seconds(b)

# Project/LAYOUT/TYPE/WxH/threads:T/simd:PATH/real_time
rows, paths = {}, []
for name, t in medians.items():
    m = re.match(r"Project/(\w+)/(\w+)/(\d+)x(\d+)/threads:(\d+)/simd:(\w+)/", name)
    if not m:
        continue
    layout, kind, w, h, threads, path = m.groups()
    rows.setdefault((layout, kind, int(w), int(h), int(threads)), {})[path] = t
    if path not in paths:
        paths.append(path)
order = ["scalar", "sse4", "avx2", "avx512", "neon"]
paths.sort(key=lambda p: order.index(p) if p in order else len(order))


def floor(kind, w, h, threads, which):
    name = (f"Floor/read/{kind}/{w}x{h}/threads:{threads}/real_time" if which == "read"
            else f"Floor/fma/{w}x{h}/threads:{threads}/real_time")
    return medians.get(name)


print("| projection | " + " | ".join(paths) + " | per pixel (fastest) | read floor | FMA floor "
      "| fastest / larger floor |")
print("|---|" + "---|" * (len(paths) + 4))
for (layout, kind, w, h, threads), by_path in sorted(rows.items()):
    best = min(by_path.values())
    read, fma = floor(kind, w, h, threads, "read"), floor(kind, w, h, threads, "fma")
    bound = max([f for f in (read, fma) if f] or [0])
    cells = [f"{layout} {kind} {w}x{h}, {threads} thread{'s' if threads > 1 else ''}"]
    cells += [fmt(by_path[p]) if p in by_path else "" for p in paths]
    cells += [f"{best / (w * h) * 1e9:.2f} ns", fmt(read) if read else "", fmt(fma) if fma else "",
              f"{best / bound:.2f}" if bound else ""]
    print("| " + " | ".join(cells) + " |")

# Merge/bracket:3/u8/WxH/threads:T/{merge,turning,project,merge+project}/real_time
merges = {}
for name, t in medians.items():
    m = re.match(r"Merge/bracket:(\d+)/u8/(\d+)x(\d+)/threads:(\d+)/"
                 r"(merge|turning|project|merge\+project)/", name)
    if m:
        n, w, h, threads, part = m.groups()
        merges.setdefault((int(w), int(h), int(threads), int(n)), {})[part] = t
if merges:
    print()
    print("| bracket merge (8-bit sRGB) | still camera (the synthetic sky at -12, -6, 0 EV) | "
          "turning camera (quarry_01 at -13, -6.5, 0 EV, 1 degree a frame) | projection of the "
          "merged frame | still merge / projection | still merge projecting as it merges, no "
          "frame written | that / projection |")
    print("|---|---|---|---|---|---|---|")
    for (w, h, threads, n), parts in sorted(merges.items()):
        merge, turning, project = parts.get("merge"), parts.get("turning"), parts.get("project")
        fused = parts.get("merge+project")
        ratio = f"{merge / project:.1f}" if merge and project else ""
        fusedRatio = f"{fused / project:.1f}" if fused and project else ""
        print(f"| {w}x{h}, {n} exposures, {threads} thread{'s' if threads > 1 else ''} | "
              f"{fmt(merge) if merge else ''} | {fmt(turning) if turning else ''} | "
              f"{fmt(project) if project else ''} | {ratio} | {fmt(fused) if fused else ''} | "
              f"{fusedRatio} |")

print()
print("| other benchmarks | median |")
print("|---|---|")
for name, t in medians.items():
    if name.startswith(("Reference/", "Brute/", "Render/", "Pipeline/")):
        label = name.replace("/real_time", "").replace("/iterations:3", "")
        print(f"| `{label}` | {fmt(t)} |")
