#!/usr/bin/env python3
"""Input latency of `hrtao view`, driven like a user with real X input (xdotool); run by scripts/bench-latency.sh.

Each run opens the scene in the viewer (the window at --size with the panel, `--stats`, `--exit-after`: the viewer
behaves as for a user and exits once it has rested a while after the last input). Its first drag is sent right after
the scene opened (during the first frames), the others during still refinement: a random 0.3-3 s after the previous
drag ended. A drag is a hover and a press (one xdotool command), then its motion (a second one); it is stamped with
CLOCK_MONOTONIC (time.monotonic) just before the motion's command, since the first motion with the button held is
the input that moves the view (the hover and the press move nothing). The viewer's --stats stamps each frame's
presentation and the latest input it answers on the same clock. A drag's latency is the presentation of the first
frame that moved the camera with input received after the stamp, minus the stamp.

With --orbit N, also the scripted `--orbit N --stats` run of the viewer (moving and still frames, convergence).
Prints a JSON summary and a Markdown table row; --out writes the JSON.
"""
import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import threading
import time

SCHEMA = "hrtao-latency/1"


def percentile(values, q):
    """The q-quantile (0..1) by linear interpolation between the sorted values (numpy's default); None if empty."""
    v = sorted(x for x in values if x is not None)
    if not v:
        return None
    pos = (len(v) - 1) * q
    lo = int(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def summary(values):
    v = [x for x in values if x is not None]
    return {
        "n": len(v),
        "median": percentile(v, 0.5),
        "p95": percentile(v, 0.95),
        "max": max(v) if v else None,
    }


def drag_latencies(frames, stamps):
    """Per stamp (sorted, monotonic ms): the first frame that answers input whose latest event was received at or
    after the stamp (and before the next stamp); its latency = presented_ms - stamp."""
    out = []
    for k, stamp in enumerate(stamps):
        nxt = stamps[k + 1] if k + 1 < len(stamps) else float("inf")
        hit = next(
            (
                (i, f)
                for i, f in enumerate(frames)
                if f.get("input") and f.get("input_last_ms") is not None and stamp <= f["input_last_ms"] < nxt
            ),
            None,
        )
        if hit is None:
            out.append({"stamp_ms": stamp, "frame": None, "latency_ms": None})
        else:
            i, f = hit
            out.append({"stamp_ms": stamp, "frame": i, "latency_ms": f["presented_ms"] - stamp,
                        "input_delay_ms": f["input_last_ms"] - stamp})
    return out


def converge_after(frames, t_ms):
    """The first converged frame presented after t_ms: (index, presented_ms - t_ms), else (None, None)."""
    for i, f in enumerate(frames):
        if f.get("converged") and f["presented_ms"] >= t_ms:
            return i, f["presented_ms"] - t_ms
    return None, None


def still_summary(frames):
    still = [f for f in frames if f.get("still")]
    return {
        "wall_ms": summary([f["wall_ms"] for f in still]),
        "interval_ms": summary([f["interval_ms"] for f in still if f["interval_ms"] > 0]),
    }


class Viewer:
    def __init__(self, cmd, env):
        self.lines = []
        self.lock = threading.Lock()
        self.proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, env=env, text=True)
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stderr:
            with self.lock:
                self.lines.append((time.monotonic(), line.rstrip()))

    def wait_for(self, needle, timeout):
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            with self.lock:
                if any(needle in l for _, l in self.lines):
                    return True
            if self.proc.poll() is not None:
                return False
            time.sleep(0.02)
        return False

    def log(self):
        with self.lock:
            return "\n".join(l for _, l in self.lines)


def xdotool(*args):
    return subprocess.run(["xdotool", *map(str, args)], check=True, capture_output=True, text=True).stdout


def find_window(pid, timeout=120):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        r = subprocess.run(["xdotool", "search", "--onlyvisible", "--pid", str(pid)], capture_output=True, text=True)
        ids = r.stdout.split()
        if ids:
            return ids[0]
        time.sleep(0.2)
    raise SystemExit("bench-latency: the viewer's window did not appear")


def drag(window, rng, view_w, view_h):
    """One left drag (orbit) in the 3D view as a hand makes it: a hover at the start, the button pressed (one
    xdotool command, which returns 75 ms after the press), then 20 moves of 4-8 px 75 ms apart (held over several
    frames: pressed and released within one or two frames of a busy viewer, egui would see a click, or a drag
    without motion) and the release. Returns the monotonic stamp (ms) taken just before the motion's command: its
    first move is sent at once, and it is the input that moves the view."""
    x = int(view_w * rng.uniform(0.3, 0.6))
    y = int(view_h * rng.uniform(0.3, 0.7))
    dx, dy = rng.choice([-1, 1]) * rng.randint(4, 8), rng.choice([-1, 0, 1])
    press = ["xdotool", "mousemove", "--window", window, x, y, "sleep", "0.05", "mousedown", "1", "sleep", "0.075"]
    subprocess.run([str(c) for c in press], check=True, capture_output=True)
    cmd = ["xdotool"]
    for k in range(1, 21):
        if k > 1:
            cmd += ["sleep", "0.075"]
        cmd += ["mousemove", "--window", window, x + k * dx, y + k * dy]
    cmd += ["mouseup", "1"]
    stamp = time.monotonic() * 1e3
    subprocess.run([str(c) for c in cmd], check=True, capture_output=True)
    return stamp


def latency_run(a, scene_args, drags, rng, workdir, k):
    stats = os.path.join(workdir, f"run{k}.json")
    cmd = [a.hrtao, "view", *scene_args, "--no-config", "--size", a.size, "--stats", stats,
           "--exit-after", str(a.rest_exit)]
    env = dict(os.environ, RUST_LOG="info")
    v = Viewer(cmd, env)
    try:
        window = find_window(v.proc.pid)
        if not v.wait_for("] opened ", a.timeout):
            raise SystemExit(f"bench-latency: the scene did not open:\n{v.log()}")
        w, h = map(int, a.size.split("x"))
        view_w = w - (0 if a.no_panel else 330)
        stamps, ends = [], []
        for d in range(drags):
            if d > 0:
                time.sleep(rng.uniform(0.3, 3.0))
            if v.proc.poll() is not None:
                break
            stamps.append(drag(window, rng, view_w, h))
            ends.append(time.monotonic() * 1e3)
        code = v.proc.wait(timeout=a.timeout)
    except BaseException:
        v.proc.kill()
        v.proc.wait()
        raise
    if code != 0:
        raise SystemExit(f"bench-latency: the viewer failed ({code}):\n{v.log()}")
    with open(stats) as f:
        s = json.load(f)
    frames = s["frames"]
    lat = drag_latencies(frames, stamps)
    for i, l in enumerate(lat):
        l["kind"] = "open" if i == 0 else "still"
    ci, conv_ms = converge_after(frames, ends[-1] if ends else 0.0)
    return {
        "stats": s,
        "drags": lat,
        "converged_frame": ci,
        "converge_ms": conv_ms,
        "log_at_rest": sum("at rest" in l for l in v.log().splitlines()),
        "sent": len(stamps),
    }


def orbit_run(a, scene_args, workdir):
    stats = os.path.join(workdir, "orbit.json")
    cmd = [a.hrtao, "view", *scene_args, "--no-config", "--size", a.size, "--orbit", str(a.orbit),
           "--stats", stats, "--exit", "--timeout", str(int(a.timeout))]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"bench-latency: the orbit run failed:\n{r.stderr}")
    with open(stats) as f:
        s = json.load(f)
    frames = s["frames"]
    last_moving = max((i for i, f in enumerate(frames) if f["moving"]), default=-1)
    after = frames[last_moving + 1:]
    conv = next((i for i, f in enumerate(after) if f["converged"]), None)
    still = after[: conv + 1] if conv is not None else after
    t0 = frames[last_moving]["presented_ms"] if last_moving >= 0 else None
    return {
        "moving_wall_ms": summary([f["wall_ms"] for f in frames if f["moving"]]),
        "still_wall_ms": summary([f["wall_ms"] for f in still]),
        "still_interval_ms": summary([f["interval_ms"] for f in still]),
        "still_frames_until_converged": len(still) if conv is not None else None,
        "converge_ms": (still[-1]["presented_ms"] - t0) if (conv is not None and t0 is not None) else None,
        "first_frame_ms": frames[0]["wall_ms"] if frames else None,
        "max_frame_after_first_ms": max((f["wall_ms"] for f in frames[1:]), default=None),
        "frames": len(frames),
    }


def roughness_run(a, scene_args, workdir):
    """The scripted `--orbit 1 --ao-out DIR --stats` run: the roughness of every frame from the camera's stop to the
    converged image, against the converged frame's (issue goal: every presented frame <= 1.25x the converged one)."""
    stats = os.path.join(workdir, "roughness.json")
    ao = os.path.join(workdir, "ao")
    cmd = [a.hrtao, "view", *scene_args, "--no-config", "--size", a.size, "--orbit", "1", "--ao-out", ao,
           "--stats", stats, "--exit", "--timeout", str(int(a.timeout))]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"bench-latency: the roughness run failed:\n{r.stderr}")
    with open(stats) as f:
        frames = json.load(f)["frames"]
    if not a.keep:
        subprocess.run(["rm", "-rf", ao])
    rough = [f.get("roughness") for f in frames]
    conv = next((i for i, f in enumerate(frames) if f["converged"]), None)
    final = rough[conv] if conv is not None else None
    still = [r for f, r in zip(frames, rough) if f["still"] and r is not None]
    peak = max(still) if still else None
    return {
        "roughness": rough,
        "internal": [f["internal"] for f in frames],
        "converged_frame": conv,
        "converged_roughness": final,
        "max_still_roughness": peak,
        "max_ratio": (peak / final) if (peak is not None and final) else None,
        "first_frame_roughness": rough[0] if rough else None,
    }


def fmt(v, unit=""):
    return "–" if v is None else f"{v:.0f}{unit}"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hrtao", default="target/release/hrtao")
    p.add_argument("--scene", help="model file (default: the bundled gearbox)")
    p.add_argument("--label", help="name in the report (default: the scene's file stem, or 'bundled')")
    p.add_argument("--drags", type=int, default=20)
    p.add_argument("--runs", type=int, default=2, help="viewer launches; each one's first drag is at opening")
    p.add_argument("--orbit", type=int, default=0, help="also the scripted --orbit N --stats run")
    p.add_argument("--roughness", action="store_true",
                   help="also the --orbit 1 --ao-out run: each frame's roughness against the converged frame's")
    p.add_argument("--size", default="1280x800")
    p.add_argument("--no-panel", action="store_true")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--rest-exit", type=float, default=4.0,
                   help="the viewer exits at its first rest this many seconds after the last input")
    p.add_argument("--timeout", type=float, default=600.0)
    p.add_argument("--out", nargs="?", const="", help="write the JSON (default path docs/bench/latency_LABEL.json)")
    p.add_argument("--keep", help="keep the viewer's stats files in this directory")
    a = p.parse_args()

    label = a.label or (os.path.splitext(os.path.basename(a.scene))[0] if a.scene else "bundled")
    scene_args = [a.scene] if a.scene else []
    if a.no_panel:
        scene_args.append("--no-panel")
    rng = random.Random(a.seed)
    workdir = a.keep or tempfile.mkdtemp(prefix="hrtao-latency-")
    os.makedirs(workdir, exist_ok=True)
    load = os.getloadavg()
    per_run = [a.drags // a.runs + (1 if k < a.drags % a.runs else 0) for k in range(a.runs)]
    runs = []
    for k, n in enumerate(per_run):
        if n == 0:
            continue
        print(f"bench-latency: {label}: run {k + 1}/{a.runs}, {n} drags", file=sys.stderr)
        runs.append(latency_run(a, scene_args, n, rng, workdir, k))
    drags = [d for r in runs for d in r["drags"]]
    frames = [f for r in runs for f in r["stats"]["frames"]]
    lat = [d["latency_ms"] for d in drags]
    result = {
        "schema": SCHEMA,
        "scene": label,
        "scene_path": a.scene,
        "device": runs[0]["stats"]["device"] if runs else None,
        "size": a.size,
        "panel": not a.no_panel,
        "seed": a.seed,
        "stamp": "motion",
        "load_avg_start": load,
        "load_avg_end": os.getloadavg(),
        "latency_ms": summary(lat),
        "latency_open_ms": summary([d["latency_ms"] for d in drags if d["kind"] == "open"]),
        "latency_still_ms": summary([d["latency_ms"] for d in drags if d["kind"] == "still"]),
        "missed_drags": sum(1 for d in drags if d["latency_ms"] is None),
        "still_frames": still_summary(frames),
        "converge_after_last_drag_ms": summary([r["converge_ms"] for r in runs]),
        "runs": [{k: v for k, v in r.items() if k != "stats"} for r in runs],
    }
    if a.orbit:
        print(f"bench-latency: {label}: --orbit {a.orbit}", file=sys.stderr)
        result["orbit"] = orbit_run(a, scene_args, workdir)
    if a.roughness:
        print(f"bench-latency: {label}: roughness (--orbit 1 --ao-out)", file=sys.stderr)
        result["roughness"] = roughness_run(a, scene_args, workdir)
    text = json.dumps(result, indent=2)
    if a.out is not None:
        out = a.out or os.path.join("docs", "bench", f"latency_{label}.json")
        os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
        with open(out, "w") as f:
            f.write(text + "\n")
        print(f"bench-latency: wrote {out}", file=sys.stderr)
    print(text)
    l, s = result["latency_ms"], result["still_frames"]
    print("\n| scene | input latency (median / p95 / max) | still frame (median / p95 / max) "
          "| still interval (median / p95 / max) | converged after the last drag | load |")
    print("|---|---|---|---|---|---|")
    c = result["converge_after_last_drag_ms"]
    print(f"| {label} | {fmt(l['median'])} / {fmt(l['p95'])} / {fmt(l['max'])} ms "
          f"| {fmt(s['wall_ms']['median'])} / {fmt(s['wall_ms']['p95'])} / {fmt(s['wall_ms']['max'])} ms "
          f"| {fmt(s['interval_ms']['median'])} / {fmt(s['interval_ms']['p95'])} / {fmt(s['interval_ms']['max'])} ms "
          f"| {fmt(c['median'] / 1e3 if c['median'] is not None else None)} s | {load[0]:.1f} |")
    if a.orbit:
        o = result["orbit"]
        print("\n| scene | moving frame (median) | still frame (median / max) | still frames until converged "
              "| time to converge |")
        print("|---|---|---|---|---|")
        conv = o["converge_ms"]
        print(f"| {label} | {fmt(o['moving_wall_ms']['median'])} ms | {fmt(o['still_wall_ms']['median'])} / "
              f"{fmt(o['still_wall_ms']['max'])} ms | {fmt(o['still_frames_until_converged'])} | "
              f"{fmt(conv / 1e3 if conv is not None else None)} s |")
    if a.roughness:
        r = result["roughness"]
        print("\n| scene | roughness: first frame | still frames' max | converged | max / converged |")
        print("|---|---|---|---|---|")
        f4 = lambda v: "–" if v is None else f"{v:.4f}"
        ratio = "–" if r["max_ratio"] is None else f"{r['max_ratio']:.2f}"
        print(f"| {label} | {f4(r['first_frame_roughness'])} | {f4(r['max_still_roughness'])} | "
              f"{f4(r['converged_roughness'])} | {ratio} |")
    if result["missed_drags"]:
        print(f"bench-latency: {result['missed_drags']} drags had no answering frame", file=sys.stderr)


if __name__ == "__main__":
    main()
