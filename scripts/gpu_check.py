#!/usr/bin/env python3
"""The `run` half of scripts/gpu-check.sh (standard library only): checks the machine, then correctness, the hash
map under overload and the benchmarks with one `hrtao` binary, and writes report.json and report.md.

Usage: gpu_check.py --bin HRTAO --root DIR --out DIR [--small] [--allow-cpu] [--step-timeout S] [--budget S]
DIR is a bundle (its manifest.json lists the scenes) or the repository (the bundled gearbox and testdata/refs).
Every hrtao command is a step with a timeout; the report is rewritten as each step starts and ends.
Exit status: 0 when every check passed, 1 when one failed (or a step timed out), 2 when the machine lacks what hrtao
needs or the device opened is a CPU (without --allow-cpu).
"""
import argparse
import ctypes
import json
import math
import os
import re
import signal
import struct
import subprocess
import sys
import time
import zlib

# Per-pixel RTAO (32 rays x 8 frames) against Blender Cycles: testdata/README.md puts a converged renderer well
# under 0.02 (crates/hrtao-core/tests/scenes_gpu.rs asserts the same bound).
RTAO_VS_CYCLES_MAE = 0.02
# HRTAO after 16 still frames against Cycles: the hash map's cells and the filter leave a bias that RTAO has not;
# measured 0.021 at 160x90 and 0.011 at 640x360 on lavapipe (the same rays on every device), so 0.05 passes only a
# working map.
HRTAO_VS_CYCLES_MAE = 0.05
# The two ray backends trace the same rays; a GPU's traversal may order hits differently (ties at equal distance).
BACKENDS_MAE = 0.005
# The overloaded map: a few hundred times fewer cells than the view needs; its image stays valid AO and near the
# normal one (coarser cells, the finest levels dropped): MAE 0.037 at 160x90 and 0.047 at 640x360 on lavapipe.
OVERLOAD_CAPACITY = 1024
OVERLOAD_VS_NORMAL_MAE = 0.15


class Missing(Exception):
    """Something the machine lacks (exit status 2)."""


class NotGpu(Missing):
    """The device hrtao opened is a CPU (lavapipe, SwiftShader): not a GPU result (exit status 2)."""


def log(msg):
    print(f"gpu-check: {msg}", flush=True)


# ---------------------------------------------------------------- images


def read_pfm(path):
    """(width, height, values) of a grey or RGB PFM (the first channel), rows top to bottom."""
    data = open(path, "rb").read()
    parts, at = [], 0
    while len(parts) < 3:
        end = data.index(b"\n", at)
        parts.append(data[at:end].decode().strip())
        at = end + 1
    kind, (w, h), scale = parts[0], map(int, parts[1].split()), float(parts[2])
    channels = 3 if kind == "PF" else 1
    fmt = ("<" if scale < 0 else ">") + "f" * (w * h * channels)
    values = struct.unpack(fmt, data[at:at + 4 * w * h * channels])[::channels]
    # PFM stores the bottom row first.
    rows = [values[y * w:(y + 1) * w] for y in range(h)][::-1]
    return w, h, [v for row in rows for v in row]


def read_exr(path):
    """(width, height, values) of a scanline OpenEXR with HALF or FLOAT channels, uncompressed or ZIP (what
    Blender wrote into testdata/refs); the R channel, rows top to bottom."""
    data = open(path, "rb").read()
    assert struct.unpack("<I", data[:4])[0] == 20000630, f"{path}: not an OpenEXR file"
    at, attrs = 8, {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack("<I", data[type_end + 1:type_end + 5])[0]
        attrs[data[at:name_end].decode()] = data[type_end + 5:type_end + 5 + size]
        at = type_end + 5 + size
    at += 1
    channels, c = [], attrs["channels"]
    while c[0] != 0:
        end = c.index(b"\0")
        pixel_type = struct.unpack("<I", c[end + 1:end + 5])[0]
        channels.append((c[:end].decode(), pixel_type))
        c = c[end + 17:]
    compression = attrs["compression"][0]
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines_per_block = {0: 1, 2: 1, 3: 16}.get(compression)
    assert lines_per_block, f"{path}: compression {compression} is not read here"
    blocks = (h + lines_per_block - 1) // lines_per_block
    offsets = struct.unpack(f"<{blocks}Q", data[at:at + 8 * blocks])
    size_of = {1: 2, 2: 4}
    row_bytes = sum(size_of[t] for _, t in channels) * w
    red = [i for i, (n, _) in enumerate(channels) if n == "R"] or [0]
    out = [0.0] * (w * h)
    for off in offsets:
        y, n = struct.unpack("<ii", data[off:off + 8])
        raw = data[off + 8:off + 8 + n]
        lines = min(lines_per_block, y1 + 1 - y)
        if compression != 0 and n < row_bytes * lines:
            # ZIP: zlib, then a delta predictor, then the two halves of the bytes interleaved.
            d = bytearray(zlib.decompress(raw))
            for i in range(1, len(d)):
                d[i] = (d[i - 1] + d[i] - 128) & 255
            half = (len(d) + 1) // 2
            raw = bytearray(len(d))
            raw[0::2], raw[1::2] = d[:half], d[half:]
            raw = bytes(raw)
        for line in range(lines):
            base = line * row_bytes
            for i, (_, t) in enumerate(channels):
                if i == red[0]:
                    fmt = "<" + ("e" if t == 1 else "f") * w
                    vals = struct.unpack(fmt, raw[base:base + size_of[t] * w])
                    row = y - y0 + line
                    out[row * w:(row + 1) * w] = vals
                base += size_of[t] * w
    return w, h, out


def read_ao(path):
    return read_exr(path) if path.endswith(".exr") else read_pfm(path)


def validity(values):
    """The image is AO: finite, within [0, 1], and some pixel is occluded (the model is in view)."""
    bad = sum(1 for v in values if not math.isfinite(v))
    finite = [v for v in values if math.isfinite(v)]
    lo, hi = (min(finite), max(finite)) if finite else (float("nan"), float("nan"))
    occluded = sum(1 for v in finite if v < 0.999)
    ok = bad == 0 and lo >= 0.0 and hi <= 1.0 + 1e-6 and occluded > 0
    return ok, {"non_finite": bad, "min": lo, "max": hi, "occluded_pixels": occluded}


def mae(a, b):
    """MAE over the pixels where either image is occluded (`hrtao_core::metrics::ao_error`)."""
    assert len(a) == len(b), "images of different sizes"
    diffs = [abs(x - y) for x, y in zip(a, b) if x < 0.999 or y < 0.999]
    return (sum(diffs) / len(diffs) if diffs else 0.0), len(diffs)


# ---------------------------------------------------------------- steps, their timeouts and the report

# The test hook: HRTAO_GPU_CHECK_HANG_STEP=NAME[,NAME...] replaces those steps' commands by a process that hangs
# (and ignores SIGTERM, as a process blocked in a driver may), so a test can prove the step is killed at its timeout.
HANG_ENV = "HRTAO_GPU_CHECK_HANG_STEP"
HANG_CODE = "import signal, time\nsignal.signal(signal.SIGTERM, signal.SIG_IGN)\nwhile True:\n    time.sleep(1)\n"


class StepError(RuntimeError):
    """A step that failed, timed out or was not run: the check that needed it fails, the run goes on."""


class Report:
    """report.json and report.md, rewritten (atomically) whenever a step starts or ends, so that a run killed from
    outside leaves what it measured, and the step it was in says `running`."""

    def __init__(self, out, data):
        self.out, self.data = out, data

    def save(self):
        self.data["seconds"] = time.time() - self.data["_t0"]
        data = {k: v for k, v in self.data.items() if not k.startswith("_")}
        for name, text in (("report.json", json.dumps(data, indent=1) + "\n"), ("report.md", markdown(data))):
            path = os.path.join(self.out, name)
            with open(path + ".tmp", "w") as f:
                f.write(text)
            os.replace(path + ".tmp", path)

    def step(self, name, **fields):
        """Adds the step, or updates the last step of that name; then saves."""
        steps = self.data["steps"]
        entry = next((s for s in reversed(steps) if s["name"] == name), None)
        if entry is None or "status" in fields and entry["status"] != "running":
            entry = {"name": name}
            steps.append(entry)
        entry.update(fields)
        self.save()
        return entry


class Result:
    def __init__(self, returncode, stdout, stderr):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def end_group(p):
    """SIGTERM to the step's process group, SIGKILL 5 s later: (exit status, how it ended); the status is None when
    the process still had not exited 10 s after SIGKILL (blocked in the kernel driver)."""
    for sig, wait in ((signal.SIGTERM, 5), (signal.SIGKILL, 10)):
        try:
            os.killpg(p.pid, sig)
        except ProcessLookupError:
            pass
        try:
            return p.wait(timeout=wait), sig.name
        except subprocess.TimeoutExpired:
            continue
    return None, "SIGKILL"


class Hrtao:
    def __init__(self, binary, out, report, step_timeout, budget):
        self.binary, self.out, self.report = binary, out, report
        self.step_timeout, self.budget = step_timeout, budget
        self.deadline = report.data["_t0"] + budget if budget > 0 else None
        self.hang = {s.strip() for s in os.environ.get(HANG_ENV, "").split(",") if s.strip()}
        self.logs = os.path.join(out, "logs")
        os.makedirs(self.logs, exist_ok=True)

    def run(self, args, step, check=True, env=None):
        """One step: `hrtao ARGS` in its own process group, killed at the step's timeout (or at the run's time
        budget, whichever comes first). Its stdout and stderr go to logs/STEP.{out,err} and hrtao.log."""
        limit, by_budget = float(self.step_timeout), False
        if self.deadline is not None and self.deadline - time.time() < limit:
            limit, by_budget = self.deadline - time.time(), True
        if limit < 1:
            note = f"not run: the run's time budget of {self.budget:.0f} s was spent"
            self.report.step(step, status="skipped", note=note)
            raise StepError(f"{step}: {note}")
        hang = step in self.hang
        cmd = [sys.executable, "-c", HANG_CODE] if hang else [self.binary, *args]
        shown = f"hrtao {' '.join(args)}"
        log(f"{step}: {shown}" + (f" (made to hang by {HANG_ENV})" if hang else ""))
        fields = {"status": "running", "command": shown, "timeout_s": round(limit, 1)}
        if hang:
            fields["hang_hook"] = f"made to hang by {HANG_ENV} (a test hook)"
        entry = self.report.step(step, **fields)
        out_path, err_path = (os.path.join(self.logs, f"{step}.{k}") for k in ("out", "err"))
        t0 = time.time()
        with open(out_path, "w") as fo, open(err_path, "w") as fe:
            p = subprocess.Popen(cmd, stdout=fo, stderr=fe, stdin=subprocess.DEVNULL, start_new_session=True,
                                 env={**os.environ, **(env or {})})
            entry["pid"] = p.pid
            self.report.save()
            try:
                rc, timed_out = p.wait(timeout=limit), False
            except subprocess.TimeoutExpired:
                (rc, how), timed_out = end_group(p), True
        seconds = time.time() - t0
        stdout, stderr = (open(path, errors="replace").read() for path in (out_path, err_path))
        with open(os.path.join(self.out, "hrtao.log"), "a") as f:
            f.write(f"$ {shown}\n{stdout}{stderr}\n")
        if timed_out:
            note = (f"killed at the run's time budget of {self.budget:.0f} s, {limit:.0f} s into the step ({how})"
                    if by_budget else f"killed at its timeout of {limit:.0f} s ({how})")
            if rc is None:
                note += "; it had not exited 10 s after SIGKILL (stuck in the driver?)"
            log(f"{step}: TIMEOUT, {note}")
            self.report.step(step, status="timeout", seconds=seconds, note=note)
            raise StepError(f"{step}: {note}")
        failed = rc != 0
        self.report.step(step, status="failed" if failed else "ok", seconds=seconds, exit_status=rc,
                         **({"note": stderr.strip()[-600:]} if failed else {}))
        if check and failed:
            raise StepError(f"{step}: hrtao exited with {rc}:\n{stderr[-4000:]}")
        return Result(rc, stdout, stderr), seconds

    def render(self, scene, name, extra, env=None):
        pfm = os.path.join(self.out, f"{name}.pfm")
        stats = os.path.join(self.out, f"{name}.stats.json")
        args = ["render", "--scene", scene["scene"], "--radius", str(scene["radius"]), "--clay"]
        args += ["--ao-out", pfm, "--stats", stats, "--out", os.path.join(self.out, f"{name}.png")]
        _, seconds = self.run(args + extra, name, env=env)
        stats = json.load(open(stats))
        # With the validation layer on (HRTAO_VALIDATION=1, as the tests run), a message is a failure.
        if stats["validation_messages"]:
            raise StepError(f"{name}: the validation layer reported {stats['validation_messages']} messages")
        return read_pfm(pfm)[2], stats, seconds


# ---------------------------------------------------------------- the machine

# Where the Vulkan loader looks for driver (ICD) files on Linux, and NVIDIA's container layout.
ICD_DIRS = ["/usr/local/nvidia/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d",
            "/usr/share/vulkan/icd.d", "/usr/local/etc/vulkan/icd.d"]
SOFTWARE = re.compile(r"llvmpipe|lavapipe|swiftshader", re.I)


def nvidia_icds():
    """The NVIDIA driver files the loader may read (VK_DRIVER_FILES / VK_ICD_FILENAMES first), each with its
    library and whether that library loads here (its dlopen error if not: a missing libX11.so.6, say)."""
    files = []
    for var in ("VK_DRIVER_FILES", "VK_ICD_FILENAMES"):
        files += [f for f in os.environ.get(var, "").split(":") if f]
    for d in ICD_DIRS:
        if os.path.isdir(d):
            files += sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(".json"))
    found, seen = [], set()
    for f in files:
        if f in seen or not os.path.isfile(f):
            continue
        seen.add(f)
        try:
            icd = json.load(open(f))["ICD"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            if "nvidia" in f.lower():
                found.append({"file": f, "error": f"unreadable: {e}"})
            continue
        lib = icd.get("library_path", "")
        if "nvidia" not in lib.lower():
            continue
        entry = {"file": f, "library_path": lib, "api_version": icd.get("api_version")}
        path = lib if os.path.isabs(lib) or "/" not in lib else os.path.join(os.path.dirname(f), lib)
        try:
            ctypes.CDLL(path)
            entry["loads"] = True
        except OSError as e:
            entry["loads"], entry["error"] = False, str(e)
        found.append(entry)
    return found


def egl_icd(icds, out):
    """An ICD file naming NVIDIA's EGL library (libEGL_nvidia.so.0, which exports the same Vulkan entry points
    without needing X11) in place of its GLX one; None when there is no GLX file to start from or the EGL library
    does not load either."""
    glx = next((i for i in icds if "GLX_nvidia" in i.get("library_path", "")), None)
    if not glx:
        return None, "no NVIDIA GLX driver file to derive the EGL one from"
    lib = glx["library_path"].replace("libGLX_nvidia", "libEGL_nvidia")
    try:
        ctypes.CDLL(lib if "/" not in lib or os.path.isabs(lib) else os.path.join(os.path.dirname(glx["file"]), lib))
    except OSError as e:
        return None, f"{lib} does not load either: {e}"
    path = os.path.join(out, "nvidia_egl_icd.json")
    icd = {"file_format_version": "1.0.0", "ICD": {"library_path": lib, "api_version": glx.get("api_version") or "1.3"}}
    with open(path, "w") as f:
        json.dump(icd, f, indent=1)
    return path, None


def parse_opened(stdout):
    # The kinds are `hrtao_core::context::kind_name`'s ("CPU (software)" has parentheses of its own).
    kinds = r"discrete GPU|integrated GPU|virtual GPU|CPU \(software\)|other"
    m = re.search(rf"^opened: (.*) \(({kinds})\), driver (.*), Vulkan (\S+), rays traced by (\w+)$", stdout, re.M)
    return m.groups() if m else None


def is_cpu(opened):
    name, kind, driver = opened[:3]
    return kind.startswith("CPU") or bool(SOFTWARE.search(name + " " + driver))


def loader_debug(hrtao, report):
    """`hrtao devices` again with VK_LOADER_DEBUG=all: its output to loader-debug.log, its errors, warnings and
    driver lines into the report."""
    try:
        p, _ = hrtao.run(["devices"], "devices_loader_debug", check=False, env={"VK_LOADER_DEBUG": "all"})
    except StepError as e:
        report.data["loader_debug"] = {"error": str(e)}
        return
    text = p.stderr + p.stdout
    with open(os.path.join(hrtao.out, "loader-debug.log"), "w") as f:
        f.write(text)
    keep = re.compile(r"ERROR|WARNING|[Ff]ail|cannot|not found|No such|\.json|Using |Found no|error", re.I)
    lines = list(dict.fromkeys(ln.rstrip() for ln in text.splitlines() if keep.search(ln)))
    report.data["loader_debug"] = {"log": "loader-debug.log", "lines": len(text.splitlines()), "excerpt": lines[-80:]}
    report.save()


def preflight(hrtao, report, allow_cpu):
    """The Vulkan loader, then a device hrtao can use (a GPU unless allow_cpu), and the ray backends it has. The
    NVIDIA driver files found, whether their libraries load, and the EGL fallback go into report["driver"]; on
    failure, the loader's debug output too."""
    try:
        ctypes.CDLL("libvulkan.so.1")
    except OSError as e:
        raise Missing(
            f"a Vulkan loader (libvulkan.so.1): {e}. The bundle carries one in lib/ (scripts/gpu-check.sh sets "
            "LD_LIBRARY_PATH); elsewhere install libvulkan1."
        )
    icds = nvidia_icds()
    driver = report.data["driver"] = {"nvidia_icds": icds, "icd_fallback": None,
                                      "VK_DRIVER_FILES": os.environ.get("VK_DRIVER_FILES")}
    for i in icds:
        if not i.get("loads"):
            log(f"NVIDIA driver {i['file']}: {i.get('library_path', '')} does not load: {i.get('error')}")
    p, _ = hrtao.run(["devices"], "devices", check=False)
    opened = parse_opened(p.stdout) if p.returncode == 0 else None
    if (not opened or is_cpu(opened)) and icds:
        # NVIDIA's GLX library failed (it needs libX11 and libXext): its EGL library exports the same driver.
        path, why = egl_icd(icds, hrtao.out)
        driver["egl_fallback"] = why or path
        if path:
            q, _ = hrtao.run(["devices"], "devices_egl", check=False, env={"VK_DRIVER_FILES": path})
            egl_opened = parse_opened(q.stdout) if q.returncode == 0 else None
            # Taken when it opens a GPU, or (--allow-cpu) any device where the GLX file opened none.
            if egl_opened and (not is_cpu(egl_opened) or allow_cpu and not opened):
                log(f"the NVIDIA GLX driver file failed; its EGL library works: VK_DRIVER_FILES={path}")
                os.environ["VK_DRIVER_FILES"] = driver["VK_DRIVER_FILES"] = path
                driver["icd_fallback"] = "egl"
                p, opened = q, egl_opened
        report.save()
    listing = p.stdout + p.stderr
    print(listing, end="", flush=True)
    if opened:
        name, kind, drv, api, default_backend = opened
        report.data["device"].update({"name": name, "kind": kind, "driver": drv, "api_version": api,
                                      "default_ray_backend": default_backend, "ray_backends": [],
                                      "devices_output": p.stdout})
        report.save()
    if not opened or (is_cpu(opened) and not allow_cpu):
        loader_debug(hrtao, report)
    if p.returncode != 0:
        if "Unable to find a Vulkan driver" in listing or "Vulkan devices (0)" in listing:
            files = os.environ.get("VK_DRIVER_FILES")
            raise Missing(
                "a Vulkan driver: the loader found none (no ICD file"
                + (f" at VK_DRIVER_FILES={files}" if files else "; set VK_DRIVER_FILES to the driver's icd.json")
                + ")" + "".join(f"; {i['file']}: {i.get('error')}" for i in icds if not i.get("loads"))
            )
        raise Missing(
            "a Vulkan device with VK_KHR_acceleration_structure and VK_KHR_ray_query or "
            "VK_KHR_ray_tracing_pipeline: each device's reason is listed above"
        )
    if not opened:
        raise StepError(f"`hrtao devices` printed no `opened:` line:\n{listing}")
    if is_cpu(opened) and not allow_cpu:
        raise NotGpu(
            f"hrtao opened {opened[0]} ({opened[1]}), driver {opened[2]}: a CPU device, whose results are not a "
            "GPU's (pass --allow-cpu to check it anyway)"
            + "".join(f"; NVIDIA driver {i['file']}: {i.get('error')}" for i in icds if not i.get("loads"))
            + "; the loader's debug output is in loader-debug.log"
        )
    for backend in ("query", "pipeline"):
        try:
            q, _ = hrtao.run(["devices", "--ray-backend", backend], f"devices_{backend}", check=False)
        except StepError:
            continue
        if q.returncode == 0:
            report.data["device"]["ray_backends"].append(backend)
        else:
            # A backend the device does not offer (an NVIDIA GPU has no ray queries) is what the probe asks, not
            # a failure: the checks run on the backends it offers.
            probe = next(e for e in reversed(report.data["steps"]) if e["name"] == f"devices_{backend}")
            probe.update(status="not offered", note=q.stderr.strip()[-600:])
            report.save()
    if not report.data["device"]["ray_backends"]:
        raise Missing("a ray backend: `hrtao devices` opened a device, but neither --ray-backend query nor pipeline")
    report.data["device"]["cpu"] = is_cpu(opened)
    report.save()


# ---------------------------------------------------------------- checks


def check(name, passed, numbers, note=""):
    log(f"{name}: {'pass' if passed else 'FAIL'} {json.dumps(numbers)}{' (' + note + ')' if note else ''}")
    return {"name": name, "passed": bool(passed), "numbers": numbers, "note": note}


def failed_check(name, error, note=""):
    """A check whose step failed, timed out or was not run."""
    first = str(error).splitlines()[0] if str(error) else type(error).__name__
    return check(name, False, {}, f"{note}: {first}" if note else first)


def correctness(hrtao, scene, size, backends):
    """Per-pixel RTAO and HRTAO by every backend against the Cycles reference of the same camera, and the
    backends against each other."""
    cam, ref = scene["cameras"][size], scene["references"][size]
    cycles = read_ao(ref)[2]
    checks, rtao_images = [], {}
    for backend in backends:
        common = ["--camera", cam, "--ray-backend", backend]
        name = f"rtao_vs_cycles_{backend}"
        try:
            rtao, stats, secs = hrtao.render(scene, f"rtao_{backend}",
                                             common + ["--mode", "rtao", "--rays", "32", "--frames", "8"])
            rtao_images[backend] = rtao
            ok, valid = validity(rtao)
            err, pixels = mae(rtao, cycles)
            checks.append(check(
                name, ok and err < RTAO_VS_CYCLES_MAE,
                {"mae": err, "limit": RTAO_VS_CYCLES_MAE, "pixels": pixels, "seconds": secs, **valid},
                f"{scene['key']} {size}, per-pixel RTAO 256 rays/pixel against Blender Cycles",
            ))
        except StepError as e:
            checks.append(failed_check(name, e))
        name = f"hrtao_vs_cycles_{backend}"
        try:
            hr, stats, secs = hrtao.render(scene, f"hrtao_{backend}", common + ["--mode", "hrtao", "--frames", "16"])
            ok, valid = validity(hr)
            err, pixels = mae(hr, cycles)
            last = stats["frames"][-1]
            checks.append(check(
                name, ok and err < HRTAO_VS_CYCLES_MAE,
                {"mae": err, "limit": HRTAO_VS_CYCLES_MAE, "pixels": pixels, "seconds": secs,
                 "load_factor": last["load_factor"], "failed_inserts": last["failed_inserts"], **valid},
                f"{scene['key']} {size}, HRTAO after 16 still frames against Blender Cycles",
            ))
        except StepError as e:
            checks.append(failed_check(name, e))
    if len(backends) == 2:
        if len(rtao_images) == 2:
            err, pixels = mae(rtao_images["query"], rtao_images["pipeline"])
            checks.append(check(
                "backends_agree", err < BACKENDS_MAE, {"mae": err, "limit": BACKENDS_MAE, "pixels": pixels},
                "per-pixel RTAO traced with ray queries and with ray-tracing pipelines",
            ))
        else:
            checks.append(failed_check("backends_agree", "a backend's RTAO image is missing"))
    return checks


def hash_overload(hrtao, scene, size):
    """HRTAO with a map far too small for the view: the map must say it is full (failed inserts, load near 1)
    while the image stays valid AO, not far from the normal map's."""
    cam = ["--camera", scene["cameras"][size], "--mode", "hrtao", "--frames", "8"]
    try:
        normal, _, _ = hrtao.render(scene, "map_normal", cam)
        small, stats, secs = hrtao.render(scene, "map_overloaded", cam + ["--hash-capacity", str(OVERLOAD_CAPACITY)])
    except StepError as e:
        return failed_check("hash_map_overload", e)
    frames = stats["frames"]
    failed = sum(f["failed_inserts"] for f in frames)
    load = max(f["load_factor"] for f in frames)
    occupied = max(f["occupied_cells"] for f in frames)
    ok, valid = validity(small)
    err, pixels = mae(small, normal)
    passed = ok and failed > 0 and 0.5 <= load <= 1.0 and occupied <= OVERLOAD_CAPACITY and err < OVERLOAD_VS_NORMAL_MAE
    return check(
        "hash_map_overload", passed,
        {"capacity": OVERLOAD_CAPACITY, "failed_inserts": failed, "max_load_factor": load,
         "max_occupied_cells": occupied, "mae_vs_normal_map": err, "mae_limit": OVERLOAD_VS_NORMAL_MAE,
         "pixels": pixels, "seconds": secs, **valid},
        f"{scene['key']} {size}: failed inserts reported, load within 0.5..1, AO finite in [0, 1]",
    )


# The validation renders: small and short (the layer slows every call), the sky light on in HRTAO mode so that its
# shader path is validated too.
VALIDATION_SIZE = ["--width", "96", "--height", "54"]
# GPU-assisted validation (shader instrumentation): VK_LAYER_ENABLES for the bundled layer (1.3.239), the
# VK_KHRONOS_VALIDATION_* setting for newer ones.
GPU_ASSISTED_ENV = {"HRTAO_VALIDATION": "1",
                    "VK_LAYER_ENABLES": "VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT",
                    "VK_KHRONOS_VALIDATION_VALIDATE_GPU_BASED": "GPU_BASED_GPU_ASSISTED"}


def validated_render(hrtao, scene, name, extra, env, bundle):
    """One small render under the Khronos validation layer: passes with the layer active and no message. Where the
    layer is not installed (a repository run) hrtao runs without it: the check is skipped then, failed in a bundle,
    which carries the layer."""
    cam = ["--camera", scene["camera"]] if scene.get("camera") else []
    try:
        img, stats, secs = hrtao.render(scene, name, cam + VALIDATION_SIZE + extra, env=env)
    except StepError as e:
        return failed_check(name, e), None
    if not stats["device"].get("validation"):
        if bundle:
            return check(name, False, {"seconds": secs}, "the bundled validation layer was not loaded"), None
        return None, f"{name}: the Khronos validation layer is not installed here"
    ok, valid = validity(img)
    return check(name, ok, {"validation_messages": stats["validation_messages"], "seconds": secs,
                            "frames": len(stats["frames"]), **valid},
                 f"{scene['key']} {VALIDATION_SIZE[1]}x{VALIDATION_SIZE[3]} under VK_LAYER_KHRONOS_validation "
                 "(synchronization validation on), no message"), None


def validation(hrtao, scene, backends, bundle):
    """One small render per AO mode and ray backend under the validation layer."""
    checks, skipped = [], []
    for backend in backends:
        for mode, extra in (("rtao", ["--mode", "rtao", "--frames", "2"]),
                            ("hrtao", ["--mode", "hrtao", "--frames", "4", "--environment", "gradient"])):
            c, skip = validated_render(hrtao, scene, f"validation_{mode}_{backend}",
                                       extra + ["--ray-backend", backend], {"HRTAO_VALIDATION": "1"}, bundle)
            checks += [c] if c else []
            skipped += [skip] if skip else []
    return checks, skipped


def gpu_assisted(hrtao, scene, device, bundle):
    """HRTAO (sky on) by the device's default backend under GPU-assisted validation: the layer instruments the
    shaders and reports out-of-bounds descriptor accesses. Not on a CPU device: on lavapipe one 32x18 frame ran
    for more than 5 minutes."""
    if device.get("cpu"):
        return None, "validation_gpu_assisted: not run on a CPU device (on lavapipe one frame takes minutes)"
    extra = ["--mode", "hrtao", "--frames", "2", "--environment", "gradient",
             "--ray-backend", device["default_ray_backend"]]
    c, skip = validated_render(hrtao, scene, "validation_gpu_assisted", extra, GPU_ASSISTED_ENV, bundle)
    if c:
        c["note"] += "; GPU-assisted validation (shader instrumentation) on"
    return c, skip


# ---------------------------------------------------------------- benchmarks


def bench(hrtao, scene, small):
    width, height = (160, 90) if small else (1920, 1080)
    nav = ["--orbit", "3", "--repeat", "1", "--settle", "4"] if small else ["--orbit", "16", "--repeat", "3"]
    out = os.path.join(hrtao.out, f"bench_{scene['key']}.json")
    args = ["bench", "--scene", scene["scene"], "--radius", str(scene["radius"]), "--label", scene["key"],
            "--width", str(width), "--height", str(height), "--no-quality", "--json", out, *nav]
    if scene.get("camera"):
        args += ["--camera", scene["camera"]]
    _, secs = hrtao.run(args, f"bench_{scene['key']}")
    r = json.load(open(out))
    if r.get("validation_messages"):
        raise StepError(f"bench {scene['key']}: the validation layer reported {r['validation_messages']} messages")

    def mode(run):
        return {
            "first_frame_gpu_ms": run["first_stats"]["gpu_total_ms"],
            "first_frame_wall_ms": run["first_stats"]["wall_ms"],
            "first_hrtao_passes_ms": run["first_stats"].get("hrtao_passes_ms"),
            "nav_frame_gpu_ms": run["nav_stats"]["gpu_total_ms"],
            "nav_frame_wall_ms": run["nav_stats"]["wall_ms"],
            "nav_hrtao_passes_ms": run["nav_stats"].get("hrtao_passes_ms"),
            "first_rays": run["first_stats"]["rays"],
        }

    return {
        "scene": scene["key"], "width": width, "height": height, "json": os.path.basename(out),
        "instanced_triangles": r["scene"]["instanced_triangles"], "seconds": secs,
        "modes": {"ours": mode(r["hrtao"]), "paper": mode(r["paper"]), "rtao": mode(r["rtao"])},
        "primary": r.get("primary"), "validation_messages": r.get("validation_messages", 0),
    }


# ---------------------------------------------------------------- layout and report


def layout(root):
    """The scenes: a bundle's manifest.json, or the repository's bundled gearbox with its Cycles references."""
    manifest = os.path.join(root, "manifest.json")
    if os.path.exists(manifest):
        scenes = json.load(open(manifest))["scenes"]
    else:
        sizes = ("160x90", "640x360")
        scenes = [{
            "key": "cycloidal", "scene": "assets/default.glb", "radius": 8.0, "camera": "assets/default.camera.json",
            "cameras": {s: f"testdata/refs/cycloidal_{s}.camera.json" for s in sizes},
            "references": {s: f"testdata/refs/cycloidal_{s}.cycles.exr" for s in sizes},
        }]
    for s in scenes:
        for k in ("scene", "camera"):
            if s.get(k):
                s[k] = os.path.join(root, s[k])
        for k in ("cameras", "references"):
            s[k] = {size: os.path.join(root, p) for size, p in s.get(k, {}).items()}
    return scenes


def markdown(report):
    d = report["device"]
    m = [f"# GPU check: {d.get('name', 'no device')}", ""]
    state = "passed" if report["passed"] else ("FAILED" if report["complete"] else "INCOMPLETE (still running, or killed)")
    m.append(f"{state}; {report['date']}; size {report['size']}; {report['seconds']:.0f} s.")
    if d:
        m += ["", f"- device: {d['name']} ({d['kind']}), driver {d['driver']}, Vulkan {d['api_version']}",
              f"- ray backends: {', '.join(d['ray_backends']) or 'not probed'} (default {d['default_ray_backend']})"]
        if d.get("cpu"):
            m.append("- **a CPU device (allowed by --allow-cpu): these are not GPU results**")
        if d.get("properties"):
            m.append(f"- properties: `{json.dumps(d['properties'])}`")
    drv = report.get("driver") or {}
    if drv.get("icd_fallback"):
        m.append(f"- driver: NVIDIA's GLX driver file failed; its EGL library was used ({drv['VK_DRIVER_FILES']})")
    for i in drv.get("nvidia_icds", []):
        if not i.get("loads"):
            m.append(f"- NVIDIA driver file {i['file']}: {i.get('library_path', '')} does not load: {i.get('error')}")
    if report.get("error"):
        m += ["", f"**{report['error']}**"]
    if report["checks"]:
        m += ["", "| check | result | numbers |", "|---|---|---|"]
    for c in report["checks"]:
        nums = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in c["numbers"].items())
        if not c["passed"] and c["note"] and not nums:
            nums = c["note"]
        m.append(f"| {c['name']} | {'pass' if c['passed'] else 'FAIL'} | {nums} |")
    if report["benches"]:
        m += ["", "| scene | size | mode | first frame GPU ms | navigation GPU ms | navigation wall ms |",
              "|---|---|---|---:|---:|---:|"]
        for b in report["benches"]:
            for name, t in b["modes"].items():
                m.append(f"| {b['scene']} | {b['width']}×{b['height']} | {name} | {t['first_frame_gpu_ms']:.2f} | "
                         f"{t['nav_frame_gpu_ms']:.2f} | {t['nav_frame_wall_ms']:.2f} |")
    if report["steps"]:
        m += ["", "| step | status | seconds | note |", "|---|---|---:|---|"]
        for s in report["steps"]:
            note = "; ".join(x for x in (s.get("note", "").replace("\n", " ").replace("|", "\\|"),
                                        s.get("hang_hook", "")) if x)
            secs = f"{s['seconds']:.1f}" if "seconds" in s else ""
            m.append(f"| {s['name']} | {s['status']} | {secs} | {note} |")
    for s in report["skipped"]:
        m.append(f"\nskipped: {s}")
    ld = report.get("loader_debug")
    if ld:
        m += ["", f"Vulkan loader debug output (VK_LOADER_DEBUG=all; all {ld.get('lines', 0)} lines in "
                  f"{ld.get('log', '-')}), errors, warnings and driver lines:", "", "```",
              *(ld.get("excerpt") or [ld.get("error", "")]), "```"]
    return "\n".join(m) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", required=True)
    ap.add_argument("--root", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--small", action="store_true")
    ap.add_argument("--allow-cpu", action="store_true", help="check a CPU device (lavapipe) too, as the tests do")
    ap.add_argument("--step-timeout", type=float, default=240.0, help="seconds one step may take (default 240)")
    ap.add_argument("--budget", type=float, default=540.0,
                    help="seconds for the whole run; steps past it are not run (default 540; 0: none)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    open(os.path.join(a.out, "hrtao.log"), "w").close()
    size = "160x90" if a.small else "640x360"
    bundle = os.path.exists(os.path.join(a.root, "manifest.json"))
    report = Report(a.out, {
        "schema": "hrtao-gpu-check/1", "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "small": a.small, "size": size, "allow_cpu": a.allow_cpu, "step_timeout_s": a.step_timeout,
        "budget_s": a.budget, "device": {}, "driver": {}, "checks": [], "benches": [], "skipped": [], "steps": [],
        "passed": False, "complete": False, "_t0": time.time()})
    report.save()
    r = report.data
    hrtao = Hrtao(a.bin, a.out, report, a.step_timeout, a.budget)
    status = 1

    def add_checks(*checks):
        r["checks"] += [c for c in checks if c]
        report.save()

    try:
        preflight(hrtao, report, a.allow_cpu)
        scenes = layout(a.root)
        main_scene = scenes[0]
        backends = r["device"]["ray_backends"]
        add_checks(*correctness(hrtao, main_scene, size, backends))
        add_checks(hash_overload(hrtao, main_scene, size))
        # Device facts as every command records them (timestamps, backend, software or not).
        stats = os.path.join(a.out, "map_normal.stats.json")
        if os.path.exists(stats):
            r["device"]["properties"] = json.load(open(stats))["device"]
            log(f"device properties: {json.dumps(r['device']['properties'])}")
        checks, skipped = validation(hrtao, main_scene, backends, bundle)
        r["skipped"] += skipped
        add_checks(*checks)
        for s in scenes:
            try:
                r["benches"].append(bench(hrtao, s, a.small))
            except StepError as e:
                add_checks(failed_check(f"bench_{s['key']}", e))
            report.save()
        if len(scenes) == 1:
            r["skipped"].append("shared scenes (san_francisco, engine): not in this bundle")
        # Last: the slowest validation, and the likeliest to hang.
        c, skip = gpu_assisted(hrtao, main_scene, r["device"], bundle)
        r["skipped"] += [skip] if skip else []
        add_checks(c)
        timed_out = [s["name"] for s in r["steps"] if s["status"] in ("timeout", "skipped")]
        r["passed"] = all(c["passed"] for c in r["checks"]) and not timed_out
        if timed_out and all(c["passed"] for c in r["checks"]):
            r["error"] = f"steps timed out or not run: {', '.join(timed_out)}"
        status = 0 if r["passed"] else 1
    except NotGpu as e:
        r["error"] = f"not a GPU: {e}"
        status = 2
    except Missing as e:
        r["error"] = f"missing: {e}"
        status = 2
    except Exception as e:  # noqa: BLE001 - whatever failed goes into the report, then the exit status
        r["error"] = f"{type(e).__name__}: {e}"
    r["complete"] = True
    report.save()
    log(f"{'passed' if r['passed'] else 'FAILED'} in {r['seconds']:.0f} s: {os.path.join(a.out, 'report.md')}")
    if r.get("error"):
        print(f"gpu-check: error: {r['error']}", file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
