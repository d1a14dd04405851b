"""Blender Cycles beside `hce bake` on the same points: the peer of tools/scripts/cycles-curve.sh.

Run by that script with the Python of a virtual environment holding `bpy` (Blender as a Python
module, pinned in cycles-curve-requirements.txt). It

  1. reads the points: the level-2 vertices of the baked scene, as `hce subdivide --level 2
     --merge --unclamped --stats` writes them (one OBJ of every object in file order, object
     space, the radiosity unclamped) and the per-object vertex and triangle counts its
     `--stats` lines give;
  2. builds the same scene in Blender from those meshes and the glTF's materials: each object
     its own mesh, diffuse (Lambertian) materials of the glTF base colour, the emitters' front
     sides emitting their `emissiveFactor` times `KHR_materials_emissive_strength` (radiance,
     so that a Cycles pixel value and hce's radiosity are the same number, SPEC.md G.1) over
     their base colour, their backs black, no world light, no clamping, 128 bounces;
  3. bakes Cycles' diffuse pass (direct + indirect, times the colour: the outgoing radiance of
     a Lambertian surface, which is hce's radiosity B of a non-emitter) into a float colour
     attribute on the points (CPU, every core): a reference of several seeds, then the curve;
  4. compares every result (Cycles and the hce bakes the shell script made) with the reference
     over the points of non-emitting objects and writes the markdown table and the CSV.

Errors are relative RMS over points and channels, sqrt(sum |a - r|^2 / sum |r|^2), r the
reference (the mean of its seeds). The reference's own noise is the standard error of that
mean: the RMS over points and channels of the seeds' spread, divided by sqrt(seeds), relative
to the reference. The error is given as measured and with the reference's noise taken out in
quadrature (sqrt(e^2 - noise^2)): each run is independent of the reference's seeds, so its
measured error is its own and the reference's noise added in quadrature.

A vertex on the edge where two walls meet lies on both; a ray Cycles starts there towards the
other wall would leave the box through the edge. Every point is therefore baked NUDGE metres
(default 0.5 mm) inside its own face, towards the middle of the face it belongs to (the points
of one object with one normal), and LIFT (10 µm) off it along its normal: the limit the
reconstructed field takes at the edge. The points are baked on a probe copy of each object that
no ray sees; the scene the rays meet keeps the exact geometry. (Moving the scene's own vertices
instead opens a crack along every edge and shrinks the light, which darkens every point, those
beside the cracks most: +3.6% bias against hce, +5% on the faces' borders, at 0.5 mm.)
"""

import argparse
import csv
import json
import math
import re
import struct
import sys
import time

import bpy
import numpy as np


def read_points(obj_path):
    """Positions, normals, colours and triangles of an OBJ that `hce subdivide` wrote."""
    pos, col, nrm, tris = [], [], [], []
    with open(obj_path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vals = [float(x) for x in parts[1:]]
                pos.append(vals[:3])
                col.append(vals[3:6] if len(vals) >= 6 else [0.0, 0.0, 0.0])
            elif parts[0] == "vn":
                nrm.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                tris.append([int(p.split("/")[0]) - 1 for p in parts[1:4]])
    return np.array(pos), np.array(nrm), np.array(col), np.array(tris, dtype=np.int64)


def read_stats(stats_path):
    """(name, vertices, triangles) per object, in order, from `hce subdivide --stats`."""
    # "object 'floor' (flat, uniform: level 2): 25 vertices, 32 triangles", or with the level
    # after the parenthesis.
    pat = re.compile(r"^object '(.*)' \(.*?\)(?:: level \d+)?: (\d+) vertices, (\d+) triangles")
    out = []
    with open(stats_path) as f:
        for line in f:
            m = pat.match(line.strip())
            if m:
                out.append((m.group(1), int(m.group(2)), int(m.group(3))))
    if not out:
        sys.exit(f"error: no object lines in {stats_path}")
    return out


def read_materials(glb_path):
    """Per node (and mesh) name: (base colour, emission) of its mesh's first primitive."""
    with open(glb_path, "rb") as f:
        data = f.read()
    if data[:4] != b"glTF":
        sys.exit(f"error: {glb_path} is not a .glb")
    length = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20 : 20 + length])
    mats = doc.get("materials", [])
    out = {}
    for node in doc.get("nodes", []):
        if "mesh" not in node:
            continue
        if any(k in node for k in ("matrix", "translation", "rotation", "scale")):
            sys.exit(f"error: node {node.get('name')!r} has a transform; this script takes "
                     "scenes whose mesh nodes have none")
        mesh = doc["meshes"][node["mesh"]]
        prim = mesh["primitives"][0]
        m = mats[prim["material"]] if "material" in prim else {}
        base = m.get("pbrMetallicRoughness", {}).get("baseColorFactor", [1, 1, 1, 1])[:3]
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get(
            "emissiveStrength", 1.0)
        emission = [e * strength for e in m.get("emissiveFactor", [0, 0, 0])]
        for name in (node.get("name"), mesh.get("name")):
            if name is not None:
                out.setdefault(name, (base, emission))
    return out


class Points:
    """The level-2 vertices split into objects, with what Blender needs to build them."""

    def __init__(self, obj_path, stats_path, glb_path):
        self.pos, self.nrm, _, tris = read_points(obj_path)
        stats = read_stats(stats_path)
        mats = read_materials(glb_path)
        if sum(s[1] for s in stats) != len(self.pos) or sum(s[2] for s in stats) != len(tris):
            sys.exit("error: the --stats counts do not add up to the OBJ's")
        self.objects = []
        v0 = t0 = 0
        for name, nv, nt in stats:
            if name not in mats:
                sys.exit(f"error: object {name!r} is not a mesh node of {glb_path}")
            base, emission = mats[name]
            self.objects.append({
                "name": name, "first": v0, "count": nv,
                "triangles": tris[t0 : t0 + nt] - v0,
                "base": base, "emission": emission,
            })
            v0 += nv
            t0 += nt
        # The points compared: those of objects that do not emit.
        keep = np.zeros(len(self.pos), dtype=bool)
        for o in self.objects:
            if max(o["emission"]) <= 0:
                keep[o["first"] : o["first"] + o["count"]] = True
        self.keep = keep
        # Points on the border of their face (an edge used by one triangle of the face), where
        # the field is read at an edge or corner and the nudge moves the Cycles point.
        border = np.zeros(len(self.pos), dtype=bool)
        for o in self.objects:
            first = o["first"]
            face = [tuple(np.round(x, 3)) for x in self.nrm[first : first + o["count"]]]
            uses = {}
            for tri in o["triangles"]:
                if len({face[i] for i in tri}) != 1:
                    continue
                for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
                    key = (min(a, b), max(a, b))
                    uses[key] = uses.get(key, 0) + 1
            for (a, b), count in uses.items():
                if count == 1:
                    border[first + a] = border[first + b] = True
        self.border = border

    def nudged(self, o, nudge, lift):
        """Object `o`'s positions, each moved `nudge` towards the middle of its face and `lift`
        along its normal."""
        p = self.pos[o["first"] : o["first"] + o["count"]].copy()
        n = self.nrm[o["first"] : o["first"] + o["count"]]
        key = [tuple(np.round(x, 3)) for x in n]
        groups = {}
        for i, k in enumerate(key):
            groups.setdefault(k, []).append(i)
        for idx in groups.values():
            c = p[idx].mean(axis=0)
            d = c - p[idx]
            length = np.linalg.norm(d, axis=1, keepdims=True)
            step = np.where(length > nudge, nudge / np.maximum(length, 1e-30), 0.0)
            p[idx] = p[idx] + d * step
        return p + lift * n


LIFT = 1e-5


def build_scene(points, nudge, threads):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.max_bounces = 128
    cy.diffuse_bounces = 128
    cy.glossy_bounces = 0
    cy.transmission_bounces = 0
    cy.transparent_max_bounces = 0
    cy.volume_bounces = 0
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.caustics_reflective = False
    cy.caustics_refractive = False
    if threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = threads
    else:
        scene.render.threads_mode = "AUTO"
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Strength"].default_value = 0.0
        bg.inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world

    baked = []
    for o in points.objects:
        first = o["first"]
        mesh = bpy.data.meshes.new(o["name"])
        exact = points.pos[first : first + o["count"]]
        mesh.from_pydata(exact.tolist(), [], o["triangles"].tolist())
        mesh.update()
        obj = bpy.data.objects.new(o["name"], mesh)
        scene.collection.objects.link(obj)
        mat = bpy.data.materials.new(o["name"])
        mat.use_nodes = True
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        nodes.clear()
        out = nodes.new("ShaderNodeOutputMaterial")
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*o["base"], 1.0)
        diffuse.inputs["Roughness"].default_value = 0.0
        emitted = max(o["emission"])
        if emitted > 0:
            emit = nodes.new("ShaderNodeEmission")
            emit.inputs["Color"].default_value = (*[e / emitted for e in o["emission"]], 1.0)
            emit.inputs["Strength"].default_value = emitted
            add = nodes.new("ShaderNodeAddShader")
            links.new(emit.outputs[0], add.inputs[0])
            links.new(diffuse.outputs[0], add.inputs[1])
            # One-sided, as hce's emitters: the back is black and emits nothing.
            black = nodes.new("ShaderNodeBsdfDiffuse")
            black.inputs["Color"].default_value = (0, 0, 0, 1)
            geom = nodes.new("ShaderNodeNewGeometry")
            mix = nodes.new("ShaderNodeMixShader")
            links.new(geom.outputs["Backfacing"], mix.inputs["Fac"])
            links.new(add.outputs[0], mix.inputs[1])
            links.new(black.outputs[0], mix.inputs[2])
            links.new(mix.outputs[0], out.inputs["Surface"])
            mat.cycles.emission_sampling = "FRONT"
        else:
            links.new(diffuse.outputs[0], out.inputs["Surface"])
            # The probe: the points, moved off the edges, on a copy no ray meets.
            probe_mesh = bpy.data.meshes.new(o["name"] + " probe")
            probe_mesh.from_pydata(points.nudged(o, nudge, LIFT).tolist(), [],
                                   o["triangles"].tolist())
            probe_mesh.update()
            probe_mesh.materials.append(mat)
            attr = probe_mesh.color_attributes.new("cycles", "FLOAT_COLOR", "POINT")
            probe_mesh.color_attributes.active_color = attr
            probe = bpy.data.objects.new(o["name"] + " probe", probe_mesh)
            for flag in ("visible_diffuse", "visible_glossy",
                         "visible_transmission", "visible_volume_scatter", "visible_shadow"):
                setattr(probe, flag, False)
            scene.collection.objects.link(probe)
            baked.append((o, probe))
        mesh.materials.append(mat)
    return scene, baked


def cycles_bake(scene, baked, n_points, samples, seed):
    """Bakes at `samples` paths per point with `seed`; (radiance per point, seconds)."""
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    for obj in bpy.context.view_layer.objects:
        obj.select_set(False)
    for _, obj in baked:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = baked[0][1]
    t = time.perf_counter()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT", "COLOR"},
                        target="VERTEX_COLORS", use_clear=True)
    seconds = time.perf_counter() - t
    values = np.zeros((n_points, 3))
    for o, obj in baked:
        data = obj.data.color_attributes["cycles"].data
        flat = np.zeros(len(data) * 4, dtype=np.float32)
        data.foreach_get("color", flat)
        values[o["first"] : o["first"] + o["count"]] = flat.reshape(-1, 4)[:, :3]
    return values, seconds


def rel_rms(a, r):
    return math.sqrt(float(np.sum((a - r) ** 2)) / float(np.sum(r ** 2)))


def rel_bias(a, r):
    return float(np.sum(a - r)) / float(np.sum(r))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", required=True, help="OBJ of hce subdivide --merge (level 2)")
    ap.add_argument("--stats", required=True, help="its --stats output")
    ap.add_argument("--scene", required=True, help="the glTF scene (.glb) baked")
    ap.add_argument("--reference-samples", type=int, default=2048)
    ap.add_argument("--reference-seeds", type=int, default=8)
    ap.add_argument("--samples", default="64 256 1024 4096")
    ap.add_argument("--hce", action="append", default=[],
                    help="NAME=SECONDS=OBJ: an hce bake, its time and its level-2 OBJ")
    ap.add_argument("--nudge", type=float, default=5e-4)
    ap.add_argument("--threads", type=int, default=0, help="0: every core")
    ap.add_argument("--markdown", required=True)
    ap.add_argument("--csv", required=True)
    args = ap.parse_args()
    if args.reference_seeds < 2:
        sys.exit("error: the reference needs at least 2 seeds to state its noise")

    points = Points(args.points, args.stats, args.scene)
    scene, baked = build_scene(points, args.nudge, args.threads)
    keep = points.keep
    n = len(points.pos)

    seeds = []
    ref_seconds = 0.0
    for k in range(args.reference_seeds):
        v, s = cycles_bake(scene, baked, n, args.reference_samples, 1000 + k)
        ref_seconds += s
        seeds.append(v[keep])
        print(f"reference seed {k + 1}/{args.reference_seeds}: {s:.1f} s", file=sys.stderr)
    seeds = np.array(seeds)
    ref = seeds.mean(axis=0)
    spread = seeds.std(axis=0, ddof=1)
    noise = math.sqrt(float(np.sum(spread ** 2)) / float(np.sum(ref ** 2))) / math.sqrt(
        args.reference_seeds)

    rows = []

    # Where a bias lies: per object, and on the faces' borders against their interiors.
    border = points.border[keep]
    groups = [("face borders", border), ("face interiors", ~border)]
    for o in points.objects:
        if max(o["emission"]) <= 0:
            mask = np.zeros(len(points.pos), dtype=bool)
            mask[o["first"] : o["first"] + o["count"]] = True
            groups.append((o["name"], mask[keep]))

    def add(peer, setting, a, seconds):
        e = rel_rms(a, ref)
        rows.append({
            "peer": peer, "setting": setting, "seconds": seconds,
            "error": e, "error_noise_removed": math.sqrt(max(e * e - noise * noise, 0.0)),
            "bias": rel_bias(a, ref),
            "biases": [rel_bias(a[m], ref[m]) for _, m in groups],
        })
        print(f"{peer} {setting}: {e * 100:.2f}% in {seconds:.1f} s, bias "
              f"{rel_bias(a, ref) * 100:+.2f}%", file=sys.stderr)

    for spec in args.hce:
        name, seconds, path = spec.split("=", 2)
        pos, _, col, _ = read_points(path)
        if pos.shape != points.pos.shape or np.max(np.abs(pos - points.pos)) > 1e-6:
            sys.exit(f"error: {path} does not have the same level-2 vertices as {args.points}")
        add("hce", name, col[keep], float(seconds))
    for k, samples in enumerate(int(s) for s in args.samples.split()):
        v, s = cycles_bake(scene, baked, n, samples, 1 + k)
        add("Cycles", f"{samples} samples", v[keep], s)

    with open(args.csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["peer", "setting", "seconds", "relative_rms", "relative_rms_noise_removed",
                    "relative_bias"])
        for r in rows:
            w.writerow([r["peer"], r["setting"], f"{r['seconds']:.2f}", f"{r['error']:.5f}",
                        f"{r['error_noise_removed']:.5f}", f"{r['bias']:+.5f}"])
    with open(args.markdown, "w") as f:
        f.write(f"Reference: Cycles, {args.reference_seeds} seeds x {args.reference_samples} "
                f"samples ({ref_seconds:.0f} s), noise {noise * 100:.2f}% (RMS between seeds "
                f"/ sqrt({args.reference_seeds})); {int(keep.sum())} level-2 vertices of the "
                f"non-emitting objects; Blender {bpy.app.version_string}.\n\n")
        f.write("| bake | error (relative RMS) | reference noise removed | bias | seconds |\n")
        f.write("|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['peer']}, {r['setting']} | {r['error'] * 100:.2f}% | "
                    f"{r['error_noise_removed'] * 100:.2f}% | {r['bias'] * 100:+.2f}% | "
                    f"{r['seconds']:.1f} |\n")
        f.write("\nBias by where the points lie (points: "
                + ", ".join(f"{name} {int(m.sum())}" for name, m in groups) + "):\n\n")
        f.write("| bake | " + " | ".join(name for name, _ in groups) + " |\n")
        f.write("|---|" + "---|" * len(groups) + "\n")
        for r in rows:
            f.write(f"| {r['peer']}, {r['setting']} | "
                    + " | ".join(f"{b * 100:+.2f}%" for b in r["biases"]) + " |\n")


if __name__ == "__main__":
    main()
