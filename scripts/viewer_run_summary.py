"""One `hrtao view --stats` result summarised for docs/bench/viewer (schema hrtao-viewer-run/1): the medians the
viewer wrote, the median UI cost per frame (the UI pass, egui's tessellation and texture uploads, recording egui,
presenting), and the time from the first frame to the converged image.

    python3 scripts/viewer_run_summary.py STATS.json OUT.json VERSION SCENE RUN
"""
import json
import statistics
import sys

src, dst, version, scene, run = sys.argv[1:]
s = json.load(open(src))
frames = s["frames"]
t = [f["presented_ms"] for f in frames]
conv = s.get("converged_frame")
ui = {
    k: statistics.median(f["cpu_ms"].get(k, 0.0) for f in frames)
    for k in ("ui", "tessellate", "egui_record", "present")
}
json.dump(
    {
        "schema": "hrtao-viewer-run/1",
        "version": version,
        "scene": scene,
        "run": int(run),
        "device": s["device"],
        "frames": len(frames),
        "median_moving_wall_ms": s["median_moving_wall_ms"],
        "median_still_wall_ms": s["median_still_wall_ms"],
        "converge_s": (t[conv] - t[0]) / 1e3 if conv is not None else None,
        "median_ui_ms": ui,
    },
    open(dst, "w"),
    indent=1,
)
converge = f"{(t[conv] - t[0]) / 1e3:.1f} s" if conv is not None else "never"
print(f"{version} {scene} run {run}: {s['median_moving_wall_ms']:.1f} ms moving, converged after {converge}")
