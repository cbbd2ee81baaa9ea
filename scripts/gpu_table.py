#!/usr/bin/env python3
"""docs/speed.md's GPU table from liveprobe-gpu-bench JSON files (medians; a later file's row
replaces an earlier one's of the same name): per frame size and pixel type, the upload (direct
and through the pixel-buffer objects), the read floor, the GPU and CPU projections; then the
bunny renders and the frame loop; the bracket merge, its workgroup sweep and its frame loop where
the runs have them. Usage: scripts/gpu_table.py RUN.json [RUN.json ...]"""
import json
import sys

rows, machine, gl = {}, [], ""
for path in sys.argv[1:]:
    d = json.load(open(path))
    machine = d["context"].get("machine", machine)
    gl = d["context"].get("gl", gl)
    for b in d["benchmarks"]:
        if b.get("aggregate_name", "median") == "median":
            rows[b["run_name"].removesuffix("/real_time")] = b

UNIT = {"ns": 1e-3, "us": 1.0, "ms": 1e3}


def us(name, counter=None):
    b = rows.get(name)
    if b is None:
        return None
    return b.get(counter) if counter else b["real_time"] * UNIT[b["time_unit"]]


def fmt(v):
    if v is None:
        return "-"
    return f"{v / 1e3:.3g} ms" if v >= 1e3 else f"{v:.3g} us"


gpu = machine[0].split(", ") if machine else ["?", "?"]
cpu = next((l.split(":", 1)[1].strip() for l in machine if l.startswith("Model name")), "?")
cores = next((l.split(":", 1)[1].strip() for l in machine if l.startswith("CPU(s)")), "?")
print(f"_GPU {gpu[0]}, driver {gpu[1]}; CPU {cpu}, {cores} cores; drawn through {gl}._")
print()
print("| frame | upload, direct | upload through PBOs: CPU write + GPU transfer | read floor (GPU) "
      "| projection on the GPU (GPU time; with readback) | / read floor | CPU projection (16 threads) |")
print("|---|---|---|---|---|---|---|")
for size in ["300x300", "1920x960", "3840x1920", "7680x3840"]:
    for t in ["f32", "u8"]:
        p = f"{t}/{size}"
        gpu, floor = us(f"Project/{p}/gpu", "gpu_us"), us(f"ReadFloor/{p}/gpu", "gpu_us")
        ratio = f"{gpu / floor:.1f}x" if gpu and floor else "-"
        pbo = (f"{fmt(us(f'Upload/{p}/pbo', 'cpu_write_us'))} + {fmt(us(f'Upload/{p}/pbo', 'gpu_us'))}"
               if f"Upload/{p}/pbo" in rows else "-")
        print(f"| {t} {size} | {fmt(us(f'Upload/{p}/direct'))} | {pbo} | {fmt(floor)} | "
              f"{fmt(gpu)}; {fmt(us(f'Project/{p}/gpu'))} | {ratio} | {fmt(us(f'Project/{p}/cpu'))} |")
print()
print("| rows per group (GPU time) | 16 | 32 | 64 | 128 | 256 | default (groups) |")
print("|---|---|---|---|---|---|---|")
for size in ["3840x1920", "7680x3840"]:
    for t in ["f32", "u8"]:
        cells = [fmt(us(f"Project/{t}/{size}/gpu/rows:{r}", "gpu_us")) for r in (16, 32, 64, 128, 256)]
        groups = us(f"Project/{t}/{size}/gpu", "groups")
        default = fmt(us(f"Project/{t}/{size}/gpu", "gpu_us"))
        cells.append(f"{default} ({groups:.0f})" if groups else default)
        print(f"| {t} {size} | " + " | ".join(cells) + " |")
print()
print("| render, the bunny with 4x MSAA | wall | GPU time |")
print("|---|---|---|")
for size in ["1920x1080", "3840x2160"]:
    n = f"Render/bunny/{size}/msaa:4"
    print(f"| {size} | {fmt(us(n))} | {fmt(us(n, 'gpu_us'))} |")
print()
print("| 8-bit 3840x1920 frame, 1920x1080 render | frame time | CPU write | GPU: transfer | "
      "projection | render |")
print("|---|---|---|---|---|---|")
for mode in ["serial", "overlapped"]:
    n = f"Frame/u8/3840x1920/render:1920x1080/{mode}"
    print(f"| {mode} | {fmt(us(n))} | {fmt(us(n, 'cpu_write_us'))} | {fmt(us(n, 'gpu_upload_us'))} | "
          f"{fmt(us(n, 'gpu_project_us'))} | {fmt(us(n, 'gpu_render_us'))} |")
if any(name.startswith("Merge/") for name in rows):
    print()
    print("| bracket of three 8-bit frames | merge and projection, one pass: wall (newest frame's "
          "upload, sums read back) | GPU time | the pass alone (frames on the GPU; GPU time) | "
          "projection alone (GPU time) | / projection | CPU merge (16 threads) |")
    print("|---|---|---|---|---|---|---|")
    for size in ["300x300", "1920x960", "3840x1920"]:
        n = f"Merge/u8x3/{size}/gpu"
        merge, alone = us(n + "/resident", "gpu_us"), us(f"Project/u8/{size}/gpu", "gpu_us")
        ratio = f"{merge / alone:.0f}x" if merge and alone else "-"
        print(f"| {size} | {fmt(us(n))} | {fmt(us(n, 'gpu_us'))} | {fmt(merge)} | {fmt(alone)} | "
              f"{ratio} | {fmt(us(f'Merge/u8x3/{size}/cpu'))} |")


def sweep(header, names):
    """A table of the still bracket's pass alone (GPU time): a row per size, a cell per name."""
    print()
    print(header)
    print("|---" * (header.count("|") - 1) + "|")
    for size in ["1920x960", "3840x1920"]:
        n = f"Merge/u8x3/{size}/gpu/resident"
        print(f"| {size} | " + " | ".join(fmt(us(n + tail, "gpu_us")) for tail in names) + " |")


if any("/resident/parts:" in name for name in rows):
    sweep("| still bracket, the pass alone (GPU time), a row in N workgroups | 1 | 2 | 4 | 8 | 16 "
          "| 32 |", [f"/parts:{n}" for n in [1, 2, 4, 8, 16, 32]])
if any("/resident/group:" in name or "/resident/bound:" in name for name in rows):
    sweep("| still bracket, the pass alone (GPU time) | workgroup of 32 | 64 | 128 | 256 "
          "| unprojected | bound: no judgement |",
          [f"/group:{g}" if g != 128 else "" for g in [32, 64, 128, 256]]
          + ["/unprojected", "/bound:no-judgement"])
if any(name.startswith("Frame/u8x3/") for name in rows):
    print()
    print("| bracketed frame: upload, merge, 1920x1080 render | background | frame time "
          "| GPU: merge | background | render |")
    print("|---|---|---|---|---|---|")
    for size in ["1920x960", "3840x1920"]:
        for tail, what in [("merge", "a still sky"), ("merge/background", "the merged frame, kept"),
                           ("merge/background:readback", "the merged frame, read back")]:
            n = f"Frame/u8x3/{size}/{tail}/render:1920x1080"
            if n in rows:
                print(f"| {size} | {what} | {fmt(us(n))} | {fmt(us(n, 'gpu_merge_us'))} | "
                      f"{fmt(us(n, 'gpu_background_us'))} | {fmt(us(n, 'gpu_render_us'))} |")
