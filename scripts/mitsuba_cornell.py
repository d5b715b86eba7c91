"""Mitsuba 3 next to glint on the whole-render benchmark's scene.

Renders scenes/cornell_box_parallelogram_light.ron as `cargo bench -p
glint-bench --bench render` does (512x512, 16 samples per pixel, independent
sampler, box pixel filter, direct light only: Lambertian surfaces and 4 light
samples per hit on the parallelogram light, no reflection rays) with Mitsuba's
`scalar_rgb` and `llvm_ad_rgb` variants and with the `glint` binary, on 1 and
2 threads in interleaved rounds, and prints the time per render (median
[min-max]) of each. Mitsuba's LLVM variant is timed after one warm-up render
that compiles its kernels (its time is printed apart).

The scene is rebuilt here by hand: the five walls are `rectangle`s, the boxes
`cube`s with glint's scale-rotate-translate, every BSDF a two-sided `diffuse`
with glint's kd, the light a one-sided `rectangle` area emitter whose radiance
is a bitmap holding glint's bilinear corner colours, `direct` integrator with
emitter_samples=4, bsdf_samples=0 and hidden emitters (glint's lights are not
seen by camera rays). What is computed differs in one way that cannot be
matched: glint's lights have no distance fall-off and no emitter cosine (SPEC
"Lights"), Mitsuba's area light has both, so the radiance is scaled by
pi r^2 / area for r the light's height above the floor and the images agree in
layout and colour, not pixel for pixel; the script prints both images' means
and their mean absolute difference after matching the means, and saves
the two side by side (glint left, brightened for viewing).

Usage: scripts/mitsuba_cornell.sh (makes the venv, finds libLLVM, builds glint)
or directly: python scripts/mitsuba_cornell.py GLINT_BINARY [--rounds N]
[--size S] [--spp N]. Writes benches/results/ (git-ignored): both images and
mitsuba_cornell.txt, which the render bench prints.
"""

import argparse
import math
import os
import re
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENE = os.path.join(ROOT, "scenes", "cornell_box_parallelogram_light.ron")
RESULTS = os.path.join(ROOT, "benches", "results")

# The same overrides as DIRECT_ONLY in benches/benches/render.rs.
GLINT_SET = [
    "shading_model=lambertian",
    "reflections=false",
    "transparency=false",
    "pixel_sampling=uniform",
    "sampler=independent",
    "shadow_samples=4",
]

# The scene file's geometry (cornell_box_parallelogram_light.ron), by hand.
WALLS = [  # (origin, edge_u, edge_v, kd)
    ((-1, 0, 1), (2, 0, 0), (0, 0, -2), (0.75, 0.75, 0.75)),  # floor
    ((-1, 2, -1), (2, 0, 0), (0, 0, 2), (0.75, 0.75, 0.75)),  # ceiling
    ((-1, 0, -1), (2, 0, 0), (0, 2, 0), (0.75, 0.75, 0.75)),  # back wall
    ((-1, 0, 1), (0, 0, -2), (0, 2, 0), (0.75, 0.1, 0.1)),  # left wall
    ((1, 0, -1), (0, 0, 2), (0, 2, 0), (0.1, 0.65, 0.1)),  # right wall
]
BOXES = [  # (translate, rotate_y degrees, scale, kd)
    ((0.35, 0.3, 0.35), -17.0, (0.6, 0.6, 0.6), (0.75, 0.75, 0.75)),  # short box
    ((-0.35, 0.6, -0.3), 20.0, (0.6, 1.2, 0.6), (0.01, 0.01, 0.01)),  # tall box
]
LIGHT_V0, LIGHT_E01, LIGHT_E02 = (-0.2, 1.99, -0.2), (0.4, 0, 0), (0, 0, 0.4)
LIGHT_COLORS = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 1, 1)]  # at v0, +e01, +e02, +both
CAMERA = dict(origin=(0, 1, 3.9), target=(0, 1, 0), up=(0, 1, 0), fov_y=40.0)


def parallelogram_matrix(o, eu, ev):
    """Maps Mitsuba's rectangle [-1,1]^2 (normal +z) onto o + s eu + t ev."""
    o, eu, ev = (np.array(x, dtype=float) for x in (o, eu, ev))
    n = np.cross(eu, ev)
    n /= np.linalg.norm(n)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = eu / 2, ev / 2, n, o + eu / 2 + ev / 2
    return m


def box_matrix(translate, rot_y_deg, scale):
    """glint's scale, rotate about y, translate, on Mitsuba's cube [-1,1]^3."""
    a = math.radians(rot_y_deg)
    r = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(np.array(scale, dtype=float) * 0.5)
    m[:3, 3] = translate
    return m


def light_bitmap(n=64):
    """glint's bilinear corner colours at the centres of an n x n texture
    (row index = v along edge02, column = u along edge01, as Mitsuba looks up)."""
    c = [np.array(x, dtype=np.float32) for x in LIGHT_COLORS]
    t = (np.arange(n, dtype=np.float32) + 0.5) / n
    u, v = t[None, :, None], t[:, None, None]
    return (1 - u) * (1 - v) * c[0] + u * (1 - v) * c[1] + (1 - u) * v * c[2] + u * v * c[3]


def scene_dict(mi, size, spp):
    def diffuse(kd):
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": kd}}}

    d = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 4, "bsdf_samples": 0, "hide_emitters": True},
        "sensor": {
            "type": "perspective",
            "fov": CAMERA["fov_y"],
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=CAMERA["origin"], target=CAMERA["target"], up=CAMERA["up"]
            ),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {
                "type": "hdrfilm",
                "width": size,
                "height": size,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
    }
    for i, (o, eu, ev, kd) in enumerate(WALLS):
        d[f"wall{i}"] = {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f(parallelogram_matrix(o, eu, ev)),
            "bsdf": diffuse(kd),
        }
    for i, (t, ry, s, kd) in enumerate(BOXES):
        d[f"box{i}"] = {"type": "cube", "to_world": mi.ScalarTransform4f(box_matrix(t, ry, s)), "bsdf": diffuse(kd)}
    # Irradiance from a small light of radiance L at height r is about
    # L * area / r^2 (times cosines), and Lambertian reflection divides by pi;
    # glint's light gives kd * colour with no fall-off: scale L to match at r.
    area = np.linalg.norm(np.cross(LIGHT_E01, LIGHT_E02))
    r = LIGHT_V0[1]
    scale = math.pi * r * r / area
    d["light"] = {
        "type": "rectangle",
        "to_world": mi.ScalarTransform4f(parallelogram_matrix(LIGHT_V0, LIGHT_E01, LIGHT_E02)),
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}},
        "emitter": {
            "type": "area",
            "radiance": {
                "type": "bitmap",
                "bitmap": mi.Bitmap(light_bitmap() * np.float32(scale)),
                "filter_type": "bilinear",
                "raw": True,
            },
        },
    }
    return d


def median_range(v):
    return statistics.median(v), min(v), max(v)


def fmt(v):
    m, lo, hi = median_range(v)
    return f"{m:.3f} s [{lo:.3f}-{hi:.3f}]"


def time_glint(binary, size, spp, threads, out):
    cmd = [binary, "render", SCENE, "--width", str(size), "--height", str(size), "--threads", str(threads), "-o", out]
    for s in GLINT_SET + [f"pixel_samples={spp}"]:
        cmd += ["--set", s]
    cpu, wall = children_cpu(), time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - wall
    busy = (children_cpu() - cpu) / wall
    m = re.search(r"spp, ([0-9.]+) s \(", p.stdout + p.stderr)
    if not m:
        sys.exit(f"cannot read glint's summary: {p.stdout}{p.stderr}")
    return float(m.group(1)), busy, wall


def children_cpu():
    """CPU seconds of the finished child processes (glint's runs)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("glint", help="the glint binary (cargo build --release)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--variants", default="scalar_rgb,llvm_ad_rgb")
    args = ap.parse_args()
    os.makedirs(RESULTS, exist_ok=True)

    import drjit as dr
    import mitsuba as mi

    threads = [1, 2]
    variants = []
    for name in args.variants.split(","):
        try:
            mi.set_variant(name)
            variants.append(name)
        except Exception as e:  # e.g. llvm_ad_rgb without libLLVM
            print(f"skipping Mitsuba {name}: {e}")
    scenes, warmup = {}, {}
    for name in variants:
        mi.set_variant(name)
        scenes[name] = mi.load_dict(scene_dict(mi, args.size, args.spp))
        # Warm-up on each thread count (the first compiles LLVM's kernels,
        # or loads them from Dr.Jit's disk cache).
        for n in threads:
            dr.set_thread_count(n)
            t = time.perf_counter()
            img = mi.render(scenes[name], spp=args.spp, seed=0)
            dr.eval(img)
            dr.sync_thread()
            warmup.setdefault(name, time.perf_counter() - t)
        mi.Bitmap(img).write(os.path.join(RESULTS, f"mitsuba_{name}.exr"))

    # Interleaved rounds: every runner once per round, in rotating order.
    runners = [("glint", n) for n in threads] + [(v, n) for v in variants for n in threads]
    times = {r: [] for r in runners}
    # CPU time over wall time per render: the threads that worked, about n for n
    # threads (glint's counts its whole process, scene loading included).
    busy = {r: [] for r in runners}
    # glint's process from start to exit (scene parsing, image output and process
    # start-up included), where its summary's render time has two decimals.
    process = {n: [] for n in threads}
    glint_exr = os.path.join(RESULTS, "glint_cornell.exr")
    for rnd in range(args.rounds):
        for k in range(len(runners)):
            who, n = runners[(rnd + k) % len(runners)]
            if who == "glint":
                t, b, w = time_glint(args.glint, args.size, args.spp, n, glint_exr)
                times[(who, n)].append(t)
                busy[(who, n)].append(b)
                process[n].append(w)
                continue
            mi.set_variant(who)
            dr.set_thread_count(n)
            cpu, t = time.process_time(), time.perf_counter()
            # One seed: a new literal seed would make the LLVM variant compile anew.
            img = mi.render(scenes[who], spp=args.spp, seed=0)
            dr.eval(img)
            dr.sync_thread()
            times[(who, n)].append(time.perf_counter() - t)
            busy[(who, n)].append((time.process_time() - cpu) / times[(who, n)][-1])

    lines = [
        f"{os.path.basename(SCENE)} {args.size}x{args.size}, {args.spp} spp, direct light only, "
        f"{args.rounds} interleaved rounds, mitsuba {mi.__version__}; seconds per render, median [min-max]"
    ]
    for who, n in runners:
        extra = ""
        if who != "glint" and n == 1:
            extra = f" (first warm-up render: {warmup[who]:.3f} s)" if who.startswith("llvm") else ""
        label = "glint (binary, whole run)" if who == "glint" else f"mitsuba {who}"
        b = median_range(busy[(who, n)])[0]
        lines.append(
            f"{label:30} {n} thread{'s' if n > 1 else ' '}: {fmt(times[(who, n)])}, {b:.2f} threads busy{extra}"
        )
    for n in threads:
        lines.append(f"{'glint (process, start to exit)':30} {n} thread{'s' if n > 1 else ' '}: {fmt(process[n])}")
    # Ratios within a round cancel most of the load other processes put on a
    # shared machine; the times alone do not.
    for v in variants:
        for n in threads:
            ratios = [g / m for g, m in zip(times[("glint", n)], times[(v, n)])]
            m, lo, hi = median_range(ratios)
            lines.append(f"glint time / mitsuba {v} time, {n} thread{'s' if n > 1 else ' '}: {m:.2f} [{lo:.2f}-{hi:.2f}]")
    for who in ["glint"] + variants:
        ratios = [a / b for a, b in zip(times[(who, 1)], times[(who, 2)])]
        m, lo, hi = median_range(ratios)
        lines.append(f"scaling 1->2 threads, {who}: {m:.2f}x [{lo:.2f}-{hi:.2f}]")
    lines.append(f"load average (1, 5, 15 min) at the end: {os.getloadavg()}")

    # Do the images look alike? Means, and the mean absolute difference once
    # the means are matched (the fall-off models differ, see the docstring).
    mi.set_variant(variants[0] if variants else "scalar_rgb")
    g = np.array(mi.Bitmap(glint_exr), dtype=np.float64)[..., :3]
    for v in variants:
        m = np.array(mi.Bitmap(os.path.join(RESULTS, f"mitsuba_{v}.exr")), dtype=np.float64)[..., :3]
        k = g.mean() / max(m.mean(), 1e-12)
        lines.append(
            f"image check {v}: mean glint {g.mean():.4f}, mitsuba {m.mean():.4f}; "
            f"mean |glint - {k:.2f} mitsuba| {np.abs(g - k * m).mean():.4f}"
        )
        side = np.clip(2 * np.concatenate([g, k * m], axis=1), 0, 1) ** (1 / 2.2)
        mi.Bitmap((255 * side).astype(np.uint8)).write(os.path.join(RESULTS, f"side_by_side_{v}.png"))
    text = "\n".join(lines) + "\n"
    print(text, end="")
    with open(os.path.join(RESULTS, "mitsuba_cornell.txt"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
