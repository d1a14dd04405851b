#!/usr/bin/env python3
"""Masks for `hce compare --mask` around the folds of a glTF scene (standard library only).

Casts one ray through each pixel centre of the camera `hce render` and `hce reference` print
(EYE:TARGET:FOV, vertical field of view in degrees, +Y up, square pixels) against the scene's
triangles, labels every pixel with the face it sees (mesh, and the direction of its triangle within 10
degrees), and
measures each pixel's distance to the nearest pixel whose 4-neighbour sees another plane (a fold,
a corner of the room, or a silhouette), in pixels (Chebyshev). It writes two grey PNGs, white
where the pixel counts:

* BAND.png: pixels of the meshes named by --objects whose distance is in [--near, --far];
* INTERIOR.png: every pixel whose distance is at least --near (away from every edge), except
  on the meshes named by --exclude (the light, whose radiance would swamp the sums).

Usage (the Cornell box of issue 20):

    tools/scripts/fold-masks.py samples/cornell-box.glb \\
        --camera 0.278,0.273,-0.8:0.278,0.273,-0.31962967:39.3077 --size 320x320 \\
        --objects short_block,tall_block --exclude light --near 3 --far 8 band.png interior.png
    hce compare render.exr ref.exr --mask band.png
"""

import argparse
import json
import math
import struct
import zlib


def read_glb(path):
    data = open(path, "rb").read()
    if data[:4] != b"glTF":
        raise SystemExit(f"{path}: not a GLB")
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + length])
    at = 20 + length
    blob = b""
    if at < len(data):
        blen = struct.unpack_from("<I", data, at)[0]
        blob = data[at + 8:at + 8 + blen]
    return doc, blob


def accessor(doc, blob, i):
    a = doc["accessors"][i]
    v = doc["bufferViews"][a["bufferView"]]
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
    fmt = {5126: "f", 5125: "I", 5123: "H", 5121: "B"}[a["componentType"]]
    size = struct.calcsize(fmt)
    stride = v.get("byteStride", size * comps)
    base = v.get("byteOffset", 0) + a.get("byteOffset", 0)
    out = []
    for k in range(a["count"]):
        vals = struct.unpack_from("<" + fmt * comps, blob, base + k * stride)
        out.append(vals if comps > 1 else vals[0])
    return out


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def node_matrix(n):
    if "matrix" in n:
        m = n["matrix"]
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    t = n.get("translation", [0, 0, 0])
    x, y, z, w = n.get("rotation", [0, 0, 0, 1])
    s = n.get("scale", [1, 1, 1])
    r = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return [[r[i][j] * s[j] for j in range(3)] + [t[i]] for i in range(3)] + [[0, 0, 0, 1]]


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def norm(a):
    l = math.sqrt(dot(a, a))
    return [x / l for x in a]


def triangles(doc, blob):
    """(mesh name, plane label, p0, p1, p2) for every triangle of every node, world space."""
    out = []
    planes = {}

    def visit(i, parent):
        n = doc["nodes"][i]
        m = mat_mul(parent, node_matrix(n))
        if "mesh" in n:
            mesh = doc["meshes"][n["mesh"]]
            name = n.get("name") or mesh.get("name") or f"mesh{n['mesh']}"
            for prim in mesh["primitives"]:
                pos = accessor(doc, blob, prim["attributes"]["POSITION"])
                idx = accessor(doc, blob, prim["indices"]) if "indices" in prim else list(range(len(pos)))
                world = [[sum(m[r][c] * (list(p) + [1])[c] for c in range(4)) for r in range(3)] for p in pos]
                for t in range(0, len(idx), 3):
                    p = [world[idx[t]], world[idx[t + 1]], world[idx[t + 2]]]
                    nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]))
                    if dot(nrm, nrm) == 0:
                        continue
                    nrm = norm(nrm)
                    # One label per mesh and direction: triangles within 10 degrees of a
                    # label's first normal are one face (SPEC.md G.2 joins them too).
                    found = [k for k, (nm, n0) in planes.items() if nm == name and dot(n0, nrm) >= math.cos(math.radians(10))]
                    label = found[0] if found else len(planes) + 1
                    planes.setdefault(label, (name, nrm))
                    out.append((name, label, p))
        for c in n.get("children", []):
            visit(c, m)

    identity = [[float(i == j) for j in range(4)] for i in range(4)]
    scene = doc["scenes"][doc.get("scene", 0)]
    for i in scene["nodes"]:
        visit(i, identity)
    return out


def write_png(path, w, h, pixels):
    raw = b"".join(b"\x00" + bytes(pixels[y * w:(y + 1) * w]) for y in range(h))

    def chunk(kind, body):
        c = struct.pack(">I", len(body)) + kind + body
        return c + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--camera", required=True, help="EYE:TARGET:FOV as hce render prints it")
    ap.add_argument("--size", required=True, help="WIDTHxHEIGHT")
    ap.add_argument("--objects", required=True, help="node names, comma-separated")
    ap.add_argument("--exclude", default="", help="node names left out of INTERIOR")
    ap.add_argument("--near", type=int, default=3)
    ap.add_argument("--far", type=int, default=8)
    ap.add_argument("band")
    ap.add_argument("interior")
    a = ap.parse_args()
    w, h = (int(x) for x in a.size.split("x"))
    eye_s, target_s, fov_s = a.camera.split(":")
    eye = [float(x) for x in eye_s.split(",")]
    target = [float(x) for x in target_s.split(",")]
    fwd = norm(sub(target, eye))
    right = norm(cross(fwd, [0, 1, 0]))
    up = cross(right, fwd)
    th = math.tan(math.radians(float(fov_s)) / 2)
    doc, blob = read_glb(a.scene)
    tris = triangles(doc, blob)
    wanted = set(a.objects.split(","))
    names = {t[0] for t in tris}
    excluded_names = set(x for x in a.exclude.split(",") if x)
    if not (wanted | excluded_names) <= names:
        missing = sorted((wanted | excluded_names) - names)
        raise SystemExit(f"no node named {missing}; the scene has {sorted(names)}")
    excluded = set(x for x in a.exclude.split(",") if x)
    label = [0] * (w * h)
    on_object = [False] * (w * h)
    left_out = [False] * (w * h)
    for py in range(h):
        for px in range(w):
            x = ((px + 0.5) / w * 2 - 1) * th * w / h
            y = (1 - (py + 0.5) / h * 2) * th
            d = [fwd[k] + x * right[k] + y * up[k] for k in range(3)]
            best, hit = math.inf, None
            for t in tris:
                p0, p1, p2 = t[2]
                e1, e2 = sub(p1, p0), sub(p2, p0)
                q = cross(d, e2)
                det = dot(e1, q)
                if abs(det) < 1e-12:
                    continue
                s = sub(eye, p0)
                u = dot(s, q) / det
                if u < 0 or u > 1:
                    continue
                r = cross(s, e1)
                v = dot(d, r) / det
                if v < 0 or u + v > 1:
                    continue
                dist = dot(e2, r) / det
                if 1e-6 < dist < best:
                    best, hit = dist, t
            if hit is not None:
                label[py * w + px] = hit[1]
                on_object[py * w + px] = hit[0] in wanted
                left_out[py * w + px] = hit[0] in excluded
    # Distance (Chebyshev, in pixels) to a pixel beside another plane, by breadth-first search.
    far = w + h
    dist = [far] * (w * h)
    queue = []
    for py in range(h):
        for px in range(w):
            i = py * w + px
            for qx, qy in ((px + 1, py), (px - 1, py), (px, py + 1), (px, py - 1)):
                if 0 <= qx < w and 0 <= qy < h and label[qy * w + qx] != label[i]:
                    dist[i] = 0
                    queue.append(i)
                    break
    head = 0
    while head < len(queue):
        i = queue[head]
        head += 1
        px, py = i % w, i // w
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                qx, qy = px + dx, py + dy
                if 0 <= qx < w and 0 <= qy < h and dist[qy * w + qx] > dist[i] + 1:
                    dist[qy * w + qx] = dist[i] + 1
                    queue.append(qy * w + qx)
    band = [255 if on_object[i] and a.near <= dist[i] <= a.far else 0 for i in range(w * h)]
    interior = [255 if label[i] and not left_out[i] and dist[i] >= a.near else 0 for i in range(w * h)]
    write_png(a.band, w, h, band)
    write_png(a.interior, w, h, interior)
    print(f"{a.band}: {sum(1 for x in band if x)} pixels; {a.interior}: {sum(1 for x in interior if x)} pixels")


if __name__ == "__main__":
    main()
