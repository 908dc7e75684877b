"""Faithful at every cube size (issue 12): the issue's table and flicker figures, for ours and pysplashsurf.

    bash bench/reference_venv.sh
    build/venv-bench/bin/python bench/smoothing_scale.py table            # 9 shared frames x c = 0.25/0.5/0.75/1.0
    build/venv-bench/bin/python bench/smoothing_scale.py flicker --cube 0.5 [--tool pysplashsurf] [--variant reach]
    python3 bench/smoothing_scale.py summary                              # the Markdown of bench/results/smoothing/
    python3 bench/smoothing_scale.py meshes --frame hilbert2_7954_particles.vtk --cube 1.0   # PLYs for the renders
    blender -b --factory-startup -P bench/smoothing_render.py -- out.png CAM TARGET SHIFT a.ply b.ply ...

Measures (analysis/scale_metrics.h; all ratios against each tool's own raw marching-cubes mesh):
- volume: enclosed volume smoothed / raw.
- droplets: raw components with 0 < volume < 1 % of the largest, each matched to the smoothed component whose
  centroid is nearest (within 2 r); the smallest kept-volume ratio.
- hfL: mean distance between a mesh and its own Taubin low-pass (uniform umbrella, lambda 0.5, mu -0.53) with
  round(1.36 (L / e)^2) passes, e the RAW mesh's mean edge length, L = 2 r; the same passes raw and smoothed;
  ratio smoothed / raw (hfl_abs: the smoothed mesh's distance in r). heat: the same against the cube-size-free
  low-pass 2 H(t) - H(2t), t = L^2 / 4. hf: 60 passes (the quality report's bumpiness).
- flicker on the 61-frame double dam break (shared/data/sequence; vertical axis z): each frame's mesh rasterised to a
  top-down height map (x 0..3, y 0..1.2, pixel r / 4, the highest surface point at each pixel centre); per pixel the
  temporal second differences of the height and of its gradient (central differences) where the surface exists in the
  three frames and did not jump by more than 2 r; medians over frames 10-60; N_HS per frame.

Variants of ours: "today" (smoothing_reach=0: the paper's 25 explicit iterations with per-component volume
restoration, the default before issue 12), "reach" (the heat flow, smoothing_reach=4.28: the default since issue 12)
or a JSON object of heat_smooth settings (reach in r, parts,
local_return, volume_correction, local_scale, return_tolerance, aggregate_size) applied to the pipeline's unsmoothed, decimated mesh and its weights,
e.g. '{"reach": 4, "parts": 1}'.
"""
import argparse
import json
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
import meniscus  # noqa: E402
from meniscus import _core  # noqa: E402

SHARED = ROOT.parent / "shared" / "data" / "splashsurf"
SEQUENCE = ROOT.parent / "shared" / "data" / "sequence"
RESULTS = ROOT / "bench" / "results" / "smoothing"
REACH = 4.28  # smoothing_reach of the "reach" variant (kMeasuredReach, post/heat_smoothing.h)
FRAMES = sorted(p.name for p in SHARED.glob("*") if p.suffix in (".vtk", ".bgeo"))  # every shared frame
THIN_TUBES = ("hilbert2_7954_particles.vtk", "hilbert_46843_particles.bgeo")
CUBES = (0.25, 0.5, 0.75, 1.0)
R, SMOOTHING_LENGTH, ISO = 0.025, 2.0, 0.6
STAGES = ("smoothing", "volume restoration")


# ---- measures ------------------------------------------------------------------------------------------------------
def _arrays(v, t):
    return np.ascontiguousarray(v, dtype=np.float32), np.ascontiguousarray(t, dtype=np.int32)


def droplet_ratios(raw_v, raw_t, v, t, radius=R):
    rv, rc = _core.component_summary(*_arrays(raw_v, raw_t))
    sv, sc = _core.component_summary(*_arrays(v, t))
    largest = rv.max() if len(rv) else 1.0
    ratios = []
    for i in np.nonzero((rv > 0) & (rv < 0.01 * largest))[0]:
        d = np.linalg.norm(sc - rc[i], axis=1) if len(sc) else np.array([])
        j = int(np.argmin(d)) if len(d) else -1
        ratios.append(0.0 if j < 0 or d[j] > 2.0 * radius else float(sv[j] / rv[i]))
    return np.array(ratios)


def measure(raw_v, raw_t, v, t, radius=R):
    raw_v, raw_t = _arrays(raw_v, raw_t)
    v, t = _arrays(v, t)
    e_raw = _core.mean_edge_length(raw_v, raw_t)
    passes = int(round(1.36 * (2.0 * radius / e_raw) ** 2))
    hfl_raw, hfl = _core.taubin_distance(raw_v, raw_t, passes), _core.taubin_distance(v, t, passes)
    hf_raw, hf = _core.taubin_distance(raw_v, raw_t, 60), _core.taubin_distance(v, t, 60)
    heat_raw, heat = _core.heat_distance(raw_v, raw_t, 2.0 * radius), _core.heat_distance(v, t, 2.0 * radius)
    drops = droplet_ratios(raw_v, raw_t, v, t, radius)
    rv, _ = _core.component_summary(raw_v, raw_t)
    sv, _ = _core.component_summary(v, t)
    check = _core.check_mesh(v, t)
    return {
        "volume_ratio": float(sv.sum() / rv.sum()),
        "droplets": int(len(drops)),
        "droplet_min": float(drops.min()) if len(drops) else None,
        "hfl_ratio": hfl / hfl_raw if hfl_raw > 0 else None,
        "hfl_abs": hfl / radius,
        "hfl_raw_abs": hfl_raw / radius,
        "hfl_passes": passes,
        "heat_ratio": heat / heat_raw if heat_raw > 0 else None,
        "heat_abs": heat / radius,
        "hf_ratio": hf / hf_raw if hf_raw > 0 else None,
        "edge_raw": e_raw / radius,
        "ok": bool(check["closed"] and check["manifold"] and check["oriented"]),
    }


# ---- runs ----------------------------------------------------------------------------------------------------------
def run_ours(positions, cube, variant="reach", keep_raw=True, threads=0):
    """dict(vertices, triangles, raw_vertices, raw_triangles, seconds, smoothing_seconds, stage_seconds, nhs, counts)."""
    common = dict(particle_radius=R, smoothing_length=SMOOTHING_LENGTH, cube_size=cube, iso_threshold=ISO, threads=threads,
                  keep_raw_mesh=keep_raw)
    if variant in ("reach", "today", "default"):  # "today"/"default": the paper's iterations, the default before the reach
        kwargs = dict(smoothing_reach=REACH if variant == "reach" else 0.0)
        start = time.perf_counter()
        mesh = meniscus.reconstruct(positions, **common, **kwargs)
        seconds = time.perf_counter() - start
        stages = mesh.stats["seconds"]
        out = dict(vertices=mesh.vertices, triangles=mesh.triangles, seconds=seconds, stage_seconds=stages,
                   smoothing_seconds=sum(stages.get(s, 0.0) for s in STAGES), nhs=mesh.weights_normalization,
                   counts=mesh.stats["counts"])
        if keep_raw:
            out.update(raw_vertices=mesh.raw.vertices, raw_triangles=mesh.raw.triangles)
        return out
    settings = dict(json.loads(variant))
    reach = settings.pop("reach", 4.0)
    smoothstep = settings.pop("weights_smoothstep", True)  # Eq. 9 on the weights the flow reads
    start = time.perf_counter()
    mesh = meniscus.reconstruct(positions, **common, smoothing_iterations=0, output_weights=True, normals=False,
                                weights_smoothstep=smoothstep)
    unsmoothed = time.perf_counter() - start
    if reach == "auto":  # the pipeline's: REACH up to c = 0.5, growing with the cube above it (smoothing_reach_at)
        reach = REACH * max(1.0, cube / 0.5)
    if isinstance(reach, str) and reach.startswith("floor"):  # "floor:K": max(4 r, K x the cube edge)
        reach = max(4.0, float(reach.split(":")[1]) * cube)
    start = time.perf_counter()
    vertices, info = _core.heat_smooth(*_arrays(mesh.vertices, mesh.triangles), mesh.attributes["weights"], reach=reach * R,
                                       particle_radius=R, threads=threads, **settings)
    smoothing = time.perf_counter() - start
    out = dict(vertices=vertices, triangles=mesh.triangles, seconds=unsmoothed + smoothing, smoothing_seconds=smoothing,
               stage_seconds=dict(mesh.stats["seconds"], smoothing=smoothing), nhs=mesh.weights_normalization,
               counts=dict(smoothing_reach=reach, applications=info["applications"]))
    if keep_raw:
        out.update(raw_vertices=mesh.raw.vertices, raw_triangles=mesh.raw.triangles)
    return out


def run_pysplashsurf(positions, cube, keep_raw=True, threads=0):
    import pysplashsurf
    start = time.perf_counter()
    result, reconstruction = pysplashsurf.reconstruction_pipeline(
        np.ascontiguousarray(positions, dtype=np.float32), particle_radius=R, smoothing_length=SMOOTHING_LENGTH,
        cube_size=cube, iso_surface_threshold=ISO, decimate_barnacles=True, mesh_smoothing_iters=25,
        mesh_smoothing_weights=True, compute_normals=True, normals_smoothing_iters=10, output_raw_mesh=keep_raw,
        multi_threading=threads != 1)
    seconds = time.perf_counter() - start
    out = dict(vertices=np.asarray(result.mesh.vertices), triangles=np.asarray(result.mesh.triangles), seconds=seconds,
               stage_seconds={}, smoothing_seconds=None, nhs=None, counts={})
    if keep_raw:
        out.update(raw_vertices=np.asarray(reconstruction.mesh.vertices), raw_triangles=np.asarray(reconstruction.mesh.triangles))
    return out


def run(tool, positions, cube, variant="default", keep_raw=True, threads=0):
    if tool == "pysplashsurf":
        return run_pysplashsurf(positions, cube, keep_raw, threads)
    return run_ours(positions, cube, variant, keep_raw, threads)


# ---- table ---------------------------------------------------------------------------------------------------------
def table(args):
    frames = args.frames.split(",") if args.frames else FRAMES
    cubes = [float(c) for c in args.cubes.split(",")] if args.cubes else CUBES
    tools = [t.split(":", 1) if ":" in t else [t, "default"] for t in args.tools.split(";")]
    output = args.output or RESULTS / "table.json"
    output.parent.mkdir(parents=True, exist_ok=True)
    rows = json.loads(output.read_text()) if args.append and output.exists() else []
    for frame in frames:
        positions = meniscus.read_particles(str(SHARED / frame)).positions
        for cube in cubes:
            for tool, variant in tools:
                r = run(tool, positions, cube, variant)
                row = measure(r["raw_vertices"], r["raw_triangles"], r["vertices"], r["triangles"])
                stages = r["stage_seconds"]
                row.update(frame=frame, cube=cube, tool=tool, variant=variant, seconds=r["seconds"],
                           smoothing_seconds=r["smoothing_seconds"],
                           smoothing_share=(r["smoothing_seconds"] / sum(stages.values())) if stages else None,
                           nhs=r["nhs"], vertices=int(len(r["vertices"])), reach=r["counts"].get("smoothing_reach"))
                rows = [x for x in rows if not (x["frame"] == frame and x["cube"] == cube and x["tool"] == tool and x["variant"] == variant)]
                rows.append(row)
                print(json.dumps({k: row[k] for k in ("frame", "cube", "tool", "variant", "volume_ratio", "droplet_min", "hfl_ratio",
                                                      "heat_ratio", "seconds")}), flush=True)
                output.write_text(json.dumps(rows, indent=1))


# ---- flicker -------------------------------------------------------------------------------------------------------
PIXEL = R / 4
BOX = (0.0, 3.0, 0.0, 1.2)


def height_map(vertices, triangles):
    nx, ny = int(round((BOX[1] - BOX[0]) / PIXEL)), int(round((BOX[3] - BOX[2]) / PIXEL))
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    x = (v[:, 0] - BOX[0]) / PIXEL - 0.5  # pixel-centre coordinates: centre i at x = i
    y = (v[:, 1] - BOX[2]) / PIXEL - 0.5
    tx, ty, tz = x[t], y[t], v[:, 2][t]
    ix0, ix1 = np.maximum(np.ceil(tx.min(1)).astype(np.int64), 0), np.minimum(np.floor(tx.max(1)).astype(np.int64), nx - 1)
    iy0, iy1 = np.maximum(np.ceil(ty.min(1)).astype(np.int64), 0), np.minimum(np.floor(ty.max(1)).astype(np.int64), ny - 1)
    wx, wy = np.maximum(ix1 - ix0 + 1, 0), np.maximum(iy1 - iy0 + 1, 0)
    count = wx * wy
    keep = count > 0
    tri = np.repeat(np.nonzero(keep)[0], count[keep])
    local = np.arange(len(tri)) - np.repeat(np.cumsum(count[keep]) - count[keep], count[keep])
    px, py = ix0[tri] + local % wx[tri], iy0[tri] + local // wx[tri]
    ax, ay = tx[tri, 0], ty[tri, 0]
    bx, by, cx, cy = tx[tri, 1] - ax, ty[tri, 1] - ay, tx[tri, 2] - ax, ty[tri, 2] - ay
    det = bx * cy - by * cx
    qx, qy = px - ax, py - ay
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (qx * cy - qy * cx) / det
        w = (bx * qy - by * qx) / det
    inside = (det != 0) & (u >= -1e-9) & (w >= -1e-9) & (u + w <= 1 + 1e-9)
    zz = tz[tri, 0] + u * (tz[tri, 1] - tz[tri, 0]) + w * (tz[tri, 2] - tz[tri, 0])
    h = np.full(nx * ny, -np.inf)
    np.maximum.at(h, (py * nx + px)[inside], zz[inside])
    h = h.reshape(ny, nx)
    h[~np.isfinite(h)] = np.nan
    return h


def _slope(h):
    gx, gy = np.full(h.shape, np.nan), np.full(h.shape, np.nan)
    gx[:, 1:-1] = (h[:, 2:] - h[:, :-2]) / (2 * PIXEL)
    gy[1:-1, :] = (h[2:, :] - h[:-2, :]) / (2 * PIXEL)
    return gx, gy


def flicker_of(maps, jump=2 * R):
    heights, slopes = [], []
    for k in range(1, len(maps) - 1):
        a, b, c = maps[k - 1], maps[k], maps[k + 1]
        ok = np.isfinite(a) & np.isfinite(b) & np.isfinite(c)
        with np.errstate(invalid="ignore"):
            ok &= (np.abs(b - a) <= jump) & (np.abs(c - b) <= jump)
        heights.append(np.abs(c - 2 * b + a)[ok])
        okn = ok.copy()
        okn[:, 1:-1] &= ok[:, 2:] & ok[:, :-2]
        okn[1:-1, :] &= ok[2:, :] & ok[:-2, :]
        okn[0, :] = okn[-1, :] = False
        okn[:, 0] = okn[:, -1] = False
        (ax, ay), (bx, by), (cx, cy) = _slope(a), _slope(b), _slope(c)
        d = np.hypot(cx - 2 * bx + ax, cy - 2 * by + ay)
        okn &= np.isfinite(d)
        slopes.append(d[okn])
    h, s = np.concatenate(heights), np.concatenate(slopes)
    return {"height_median": float(np.median(h)), "slope_median": float(np.median(s)), "pixels": int(len(h)),
            "slope_pixels": int(len(s))}


def flicker(args):
    # frames first .. last are rasterised: second differences at first + 1 .. last - 1 (as the research measured)
    maps, nhs, seconds = [], [], []
    for frame in range(args.first, args.last + 1):
        positions = meniscus.read_particles(str(SEQUENCE / f"double_dam_break_{frame:04d}.vtk")).positions
        r = run(args.tool, positions, args.cube, args.variant, keep_raw=False)
        seconds.append(r["seconds"])
        nhs.append(r["nhs"])
        maps.append(height_map(r["vertices"], r["triangles"]))
    result = {"tool": args.tool, "variant": args.variant, "cube": args.cube, "frames": [args.first, args.last], **flicker_of(maps),
              "nhs": nhs, "seconds_median": float(np.median(seconds))}
    name = args.name or (args.variant if args.variant in ("default", "reach", "today") else "custom")
    output = args.output or RESULTS / f"flicker_{args.tool}_{name}_c{args.cube}.json"
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(result, indent=1))
    print(json.dumps({k: v for k, v in result.items() if k != "nhs"}))


# ---- meshes for renders -------------------------------------------------------------------------------------------
def meshes(args):
    """raw / before (the paper's 25 explicit iterations) / ours (reach 4.28 r) / pysplashsurf (with --tools) as PLY files."""
    positions = meniscus.read_particles(str(SHARED / args.frame)).positions
    folder = args.output or ROOT / "build" / "smoothing_meshes"
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{args.frame.split('_particles')[0].split('.')[0]}_c{args.cube}"
    paths = []
    for variant in ("today", "reach"):
        r = run_ours(positions, args.cube, variant)
        if variant == "today":
            meniscus.Mesh(vertices=r["raw_vertices"], triangles=r["raw_triangles"]).write(str(folder / f"{stem}_raw.ply"))
            paths.append(folder / f"{stem}_raw.ply")
        path = folder / f"{stem}_{'before' if variant == 'today' else 'ours'}.ply"
        meniscus.Mesh(vertices=r["vertices"], triangles=r["triangles"]).write(str(path))
        paths.append(path)
    if args.pysplashsurf:
        r = run_pysplashsurf(positions, args.cube, keep_raw=False)
        path = folder / f"{stem}_pysplashsurf.ply"
        meniscus.Mesh(vertices=np.ascontiguousarray(r["vertices"], np.float32), triangles=np.ascontiguousarray(r["triangles"], np.int32)).write(str(path))
        paths.append(path)
    print(" ".join(str(p) for p in paths))


# ---- summary -------------------------------------------------------------------------------------------------------
def _f(x, spec=".3f"):
    return "–" if x is None else format(x, spec)


def summary(args):
    folder = args.folder or RESULTS
    rows = json.loads((folder / "table.json").read_text())
    label = {("meniscus", "reach"): "ours, reach 4.28 r", ("meniscus", "today"): "ours, reach 0 (25 explicit)", ("pysplashsurf", "default"): "pysplashsurf"}
    lines = ["## Per frame", "",
             "| frame | c | tool | volume | droplets min | hfL | hfL abs (r) | heat | hf | smoothing s | share | ok |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        tool = label.get((r["tool"], r["variant"]), f"ours {r['variant']}")
        lines.append(f"| {r['frame'].split('_particles')[0]} | {r['cube']} | {tool} | {r['volume_ratio']:.4f} | {_f(r['droplet_min'])} | "
                     f"{_f(r['hfl_ratio'])} | {_f(r['hfl_abs'], '.4f')} | {_f(r['heat_ratio'])} | {_f(r['hf_ratio'])} | "
                     f"{_f(r['smoothing_seconds'], '.3f')} | {_f(None if r['smoothing_share'] is None else 100 * r['smoothing_share'], '.0f')} | "
                     f"{'yes' if r['ok'] else 'NO'} |")
    per = ["## Per tool and cube size (9 shared frames)", "",
           "| tool | c | max abs(volume - 1) | min droplet | max hfL (no tubes) | hfL hilbert / hilbert2 | median hfL abs (r) | "
           "median heat | median smoothing share | closed+manifold+oriented |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    keys = sorted({(r["tool"], r["variant"]) for r in rows})
    for key in keys:
        for cube in sorted({r["cube"] for r in rows}):
            sel = [r for r in rows if (r["tool"], r["variant"]) == key and r["cube"] == cube]
            if not sel:
                continue
            notube = [r["hfl_ratio"] for r in sel if r["frame"] not in THIN_TUBES and r["hfl_ratio"] is not None]
            tubes = {r["frame"]: r["hfl_ratio"] for r in sel if r["frame"] in THIN_TUBES}
            drops = [r["droplet_min"] for r in sel if r["droplet_min"] is not None]
            shares = [r["smoothing_share"] for r in sel if r["smoothing_share"] is not None]
            per.append(f"| {label.get(key, 'ours ' + key[1])} | {cube} | {max(abs(r['volume_ratio'] - 1) for r in sel):.4f} | "
                       f"{_f(min(drops) if drops else None)} | {_f(max(notube) if notube else None)} | "
                       f"{_f(tubes.get(THIN_TUBES[1]))} / {_f(tubes.get(THIN_TUBES[0]))} | "
                       f"{np.median([r['hfl_abs'] for r in sel]):.4f} | {np.median([r['heat_ratio'] for r in sel]):.3f} | "
                       f"{_f(100 * float(np.median(shares)) if shares else None, '.0f')} % | "
                       f"{'all' if all(r['ok'] for r in sel) else 'NOT all'} |")
    flick = ["## Flicker (double dam break, frames 10-60, medians)", "",
             "| tool | variant | c | height (m) | slope | slope / pysplashsurf | pixels |", "|---|---|---:|---:|---:|---:|---:|"]
    runs = [json.loads(p.read_text()) for p in sorted(folder.glob("flicker_*.json"))]
    reference = {r["cube"]: r["slope_median"] for r in runs if r["tool"] == "pysplashsurf"}
    for r in sorted(runs, key=lambda r: (r["cube"], r["tool"], str(r["variant"]))):
        ratio = r["slope_median"] / reference[r["cube"]] if r["cube"] in reference else None
        flick.append(f"| {r['tool']} | {r['variant']} | {r['cube']} | {r['height_median']:.5f} | {r['slope_median']:.4f} | {_f(ratio)} | {r['pixels']} |")
    text = "\n".join(["# Faithful at every cube size: results", "", "Made by `bench/smoothing_scale.py summary`.", ""] + per + [""] + flick + [""] + lines) + "\n"
    (folder / "summary.md").write_text(text)
    print(text)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    t = sub.add_parser("table")
    t.add_argument("--frames")
    t.add_argument("--cubes")
    t.add_argument("--tools", default="meniscus:reach;meniscus:today;pysplashsurf", help="';'-separated tool[:variant]")
    t.add_argument("--output", type=pathlib.Path)
    t.add_argument("--append", action="store_true", help="keep the rows of other runs in the output")
    f = sub.add_parser("flicker")
    f.add_argument("--tool", default="meniscus")
    f.add_argument("--variant", default="reach")
    f.add_argument("--name", help="file name part for a JSON variant")
    f.add_argument("--cube", type=float, default=0.5)
    f.add_argument("--first", type=int, default=10)
    f.add_argument("--last", type=int, default=60)
    f.add_argument("--output", type=pathlib.Path)
    m = sub.add_parser("meshes")
    m.add_argument("--frame", required=True)
    m.add_argument("--cube", type=float, default=1.0)
    m.add_argument("--pysplashsurf", action="store_true")
    m.add_argument("--output", type=pathlib.Path)
    s = sub.add_parser("summary")
    s.add_argument("--folder", type=pathlib.Path)
    args = parser.parse_args()
    {"table": table, "flicker": flicker, "meshes": meshes, "summary": summary}[args.command](args)


if __name__ == "__main__":
    main()
