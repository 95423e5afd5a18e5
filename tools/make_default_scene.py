#!/usr/bin/env python3
"""Writes weft's built-in default scene: assets/default.glb and assets/default.gltf (+ default.bin).

A cloth draped over a ball on a floor, a small metal ball beside it, lit by a warm directional key
light, a cool point light and a spot light, seen by one perspective camera from the front.

Python 3 standard library only; the output is byte-for-byte deterministic. Y is up, units are
metres. Run from anywhere:  python3 tools/make_default_scene.py
"""

import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ASSETS = os.path.join(os.path.dirname(HERE), "assets")

# --- small vector helpers -------------------------------------------------------------------------


def add(a, b):
    return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def scale(a, s):
    return [a[0] * s, a[1] * s, a[2] * s]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def length(a):
    return math.sqrt(dot(a, a))


def normalize(a):
    n = length(a)
    return scale(a, 1.0 / n)


def smoothstep(e0, e1, x):
    t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


# --- parametric surfaces --------------------------------------------------------------------------
#
# A surface is a function f(u, v) -> position over [0,1]^2. Normals come from the analytic
# function given (or from finite differences), tangents from the u-derivative, made orthogonal to
# the normal; the tangent's w is the sign that makes w * cross(n, t) point along -v of the texture
# coordinates: up the image, where a glTF normal map's +Y points (the sign Khronos'
# NormalTangentMirrorTest carries, and what weft's loader generates with MikkTSpace).

EPS = 1e-4


def grid_mesh(f, nu, nv, uv_scale, normal_fn=None, v_clamp=0.0):
    """Samples f on an (nu+1) x (nv+1) grid. Returns (positions, normals, tangents, uvs, indices).

    The texture coordinate of grid point (u, v) is (u * uv_scale[0], v * uv_scale[1]), shifted by
    -uv_scale[1] in v when that is negative (so v can run against the surface parameter).
    `v_clamp` keeps derivative evaluation away from degenerate rows (sphere poles).
    """
    pos, nrm, tan, uvs = [], [], [], []
    for j in range(nv + 1):
        v = j / nv
        for i in range(nu + 1):
            u = i / nu
            p = f(u, v)
            vd = min(max(v, v_clamp), 1.0 - v_clamp)
            du = sub(f(u + EPS, vd), f(u - EPS, vd))
            dv = sub(f(u, min(vd + EPS, 1.0)), f(u, max(vd - EPS, 0.0)))
            if normal_fn is not None:
                n = normal_fn(u, v)
            else:
                # Normal on the side where (du, dv) is counter-clockwise with the texture's v
                # flipped (v grows downward in an image): cross(dv, du).
                n = normalize(cross(dv, du))
            t = normalize(sub(du, scale(n, dot(n, du))))
            w = 1.0 if dot(cross(n, t), dv) * uv_scale[1] <= 0.0 else -1.0
            pos.append(p)
            nrm.append(n)
            tan.append(t + [w])
            uvs.append([u * uv_scale[0], v * uv_scale[1] - min(uv_scale[1], 0.0)])
    indices = []
    row = nu + 1
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = j * row + i, j * row + i + 1, (j + 1) * row + i, (j + 1) * row + i + 1
            for tri in ((a, c, b), (b, c, d)):
                # Wind each triangle counter-clockwise as seen from the side its normals face.
                p0, p1, p2 = pos[tri[0]], pos[tri[1]], pos[tri[2]]
                fn = cross(sub(p1, p0), sub(p2, p0))
                navg = add(add(nrm[tri[0]], nrm[tri[1]]), nrm[tri[2]])
                if length(fn) < 1e-12:
                    continue  # degenerate (sphere pole): drop it
                if dot(fn, navg) < 0.0:
                    tri = (tri[0], tri[2], tri[1])
                indices.extend(tri)
    return pos, nrm, tan, uvs, indices


# --- the objects ----------------------------------------------------------------------------------

BALL_RADIUS = 0.5          # the ball under the cloth, resting on the floor at the origin
BALL_CENTER = [0.0, BALL_RADIUS, 0.0]
CLOTH_GAP = 0.015          # how far the cloth rests above the ball
CLOTH_HALF = 1.2           # the flat cloth is 2.4 m x 2.4 m
CLOTH_CELLS = 96           # 96 x 96 quads
CLOTH_UV_REPEAT = 8.0      # texture coordinates span [0, 8]
CLOTH_ROTATION = math.radians(45.0)  # a corner of the cloth points at the camera
DETACH_ANGLE = 1.0         # radians from the top where the cloth leaves the ball
FLOOR_LIFT = 0.004         # the cloth on the floor floats this much above it
BEND_RADIUS = 0.12         # where the hanging cloth meets the floor it bends with this radius
FOLDS = 8                  # radial folds around the skirt
FOLD_DEPTH = 0.10          # their height (m), reached well below the ball's top


def sphere(u, v):
    theta = v * math.pi
    phi = u * 2.0 * math.pi
    return [
        BALL_RADIUS * math.sin(theta) * math.cos(phi),
        BALL_RADIUS * math.cos(theta),
        -BALL_RADIUS * math.sin(theta) * math.sin(phi),
    ]


def sphere_normal(u, v):
    return normalize(sphere(u, v)) if 0.0 < v < 1.0 else [0.0, 1.0 if v < 0.5 else -1.0, 0.0]


def drape_profile(s):
    """The cloth's meridian: arc length s from the top -> (rho, y, outward normal in (rho, y))."""
    rc = BALL_RADIUS + CLOTH_GAP
    cy = BALL_CENTER[1]
    s_detach = rc * DETACH_ANGLE
    if s <= s_detach:
        th = s / rc
        return rc * math.sin(th), cy + rc * math.cos(th), (math.sin(th), math.cos(th))
    # A straight cone along the ball's tangent, then an arc of BEND_RADIUS onto the floor.
    rho0 = rc * math.sin(DETACH_ANGLE)
    y0 = cy + rc * math.cos(DETACH_ANGLE)
    d = (math.cos(DETACH_ANGLE), -math.sin(DETACH_ANGLE))
    line_len_to_floor = (y0 - FLOOR_LIFT) / -d[1]
    t = BEND_RADIUS * math.tan(DETACH_ANGLE / 2.0)
    line_len = line_len_to_floor - t
    s1 = s_detach + line_len
    if s <= s1:
        a = s - s_detach
        return rho0 + d[0] * a, y0 + d[1] * a, (-d[1], d[0])
    # Bend: turn from direction angle -DETACH_ANGLE up to 0 around a centre above the floor.
    arc_len = BEND_RADIUS * DETACH_ANGLE
    start_rho = rho0 + d[0] * line_len
    start_y = y0 + d[1] * line_len
    n0 = (-d[1], d[0])  # outward normal at the start of the arc, points at the arc's centre
    centre = (start_rho + n0[0] * BEND_RADIUS, start_y + n0[1] * BEND_RADIUS)
    if s <= s1 + arc_len:
        ang = -DETACH_ANGLE + (s - s1) / BEND_RADIUS  # direction angle of the curve
        nrm = (-math.sin(ang), math.cos(ang))
        return centre[0] - nrm[0] * BEND_RADIUS, centre[1] - nrm[1] * BEND_RADIUS, nrm
    end_rho = centre[0]
    return end_rho + (s - s1 - arc_len), FLOOR_LIFT, (0.0, 1.0)


def fold_amount(s, phi):
    """Outward displacement of the folds: zero on the ball, growing down the skirt, never negative
    (so the folds never push the cloth into the ball or the floor)."""
    s_detach = (BALL_RADIUS + CLOTH_GAP) * DETACH_ANGLE
    grow = smoothstep(s_detach, s_detach + 0.45, s)
    wave = 0.5 - 0.5 * math.cos(FOLDS * phi + 0.7 * math.sin(3.0 * phi + 0.4))
    return FOLD_DEPTH * grow * wave


def cloth(u, v):
    # Flat cloth coordinates, rotated so a corner points toward +Z (the camera).
    fx = (u * 2.0 - 1.0) * CLOTH_HALF
    fz = (v * 2.0 - 1.0) * CLOTH_HALF
    c, sn = math.cos(CLOTH_ROTATION), math.sin(CLOTH_ROTATION)
    x, z = c * fx - sn * fz, sn * fx + c * fz
    s = math.hypot(x, z)
    phi = math.atan2(z, x)
    rho, y, (nr, ny) = drape_profile(s)
    h = fold_amount(s, phi)
    rho += nr * h
    y += ny * h
    return [rho * math.cos(phi), y, rho * math.sin(phi)]


FLOOR_CELLS = 16


def floor_quad(u, v):
    half = 3.0
    return [(u * 2.0 - 1.0) * half, 0.0, (v * 2.0 - 1.0) * half]


# --- nodes, lights, camera ------------------------------------------------------------------------


def look_rotation(eye, target):
    """Quaternion (x, y, z, w) of a node at `eye` whose -Z looks at `target`, +Y as up as possible."""
    fwd = normalize(sub(target, eye))
    z = scale(fwd, -1.0)
    x = normalize(cross([0.0, 1.0, 0.0], z))
    y = cross(z, x)
    # Rotation matrix columns x, y, z -> quaternion.
    m00, m01, m02 = x[0], y[0], z[0]
    m10, m11, m12 = x[1], y[1], z[1]
    m20, m21, m22 = x[2], y[2], z[2]
    tr = m00 + m11 + m22
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q = [(m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s]
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2.0
        q = [0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s]
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2.0
        q = [(m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s]
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2.0
        q = [(m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s]
    return [r(c, 7) for c in q]


def r(x, digits=6):
    """Rounds for the JSON text (keeps it short and stable); -0.0 becomes 0.0."""
    x = round(x, digits)
    return 0.0 if x == 0.0 else x


METAL_BALL_RADIUS = 0.22
METAL_BALL_SPOT = [0.85, 0.0, 0.85]  # front right, between two corners of the cloth
CAMERA_EYE = [0.0, 1.5, 3.5]
CAMERA_TARGET = [0.0, 0.4, 0.3]
KEY_FROM = [2.0, 4.0, 2.6]          # directional: only its direction matters
POINT_AT = [-1.3, 1.7, 1.0]
SPOT_AT = [0.9, 2.3, -1.6]
SPOT_TARGET = [0.0, 0.9, 0.0]


# --- glTF writing ---------------------------------------------------------------------------------


class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data), "target": target})
        self.bin.extend(data)
        return len(self.views) - 1

    def floats(self, rows, kind, with_bounds=False):
        n = len(rows[0])
        data = b"".join(struct.pack("<%df" % n, *row) for row in rows)
        acc = {"bufferView": self._view(data, 34962), "componentType": 5126, "count": len(rows), "type": kind}
        if with_bounds:
            # Bounds of the values as stored (rounded to f32), as the spec requires for POSITION.
            stored = [struct.unpack("<%df" % n, struct.pack("<%df" % n, *row)) for row in rows]
            acc["min"] = [min(row[k] for row in stored) for k in range(n)]
            acc["max"] = [max(row[k] for row in stored) for k in range(n)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        if max(idx) < 65536:
            data, ctype = struct.pack("<%dH" % len(idx), *idx), 5123
        else:
            data, ctype = struct.pack("<%dI" % len(idx), *idx), 5125
        self.accessors.append({"bufferView": self._view(data, 34963), "componentType": ctype, "count": len(idx), "type": "SCALAR"})
        return len(self.accessors) - 1

    def primitive(self, mesh, material):
        pos, nrm, tan, uvs, idx = mesh
        return {
            "attributes": {
                "POSITION": self.floats(pos, "VEC3", with_bounds=True),
                "NORMAL": self.floats(nrm, "VEC3"),
                "TANGENT": self.floats(tan, "VEC4"),
                "TEXCOORD_0": self.floats(uvs, "VEC2"),
            },
            "indices": self.indices(idx),
            "material": material,
        }


def check_clearances(cloth_pos, metal_centre):
    """The cloth must stay clear of both balls and above the floor."""
    for p in cloth_pos:
        assert length(sub(p, BALL_CENTER)) > BALL_RADIUS + 0.005, p
        assert length(sub(p, metal_centre)) > METAL_BALL_RADIUS + 0.02, p
        assert p[1] > 0.002, p


def build():
    b = Builder()
    ball = grid_mesh(sphere, 64, 32, (1.0, 1.0), normal_fn=sphere_normal, v_clamp=0.02)
    # Texture v runs against the surface's v on the cloth and the floor (w = -1 on both; the
    # spheres have w = +1).
    cloth_mesh = grid_mesh(cloth, CLOTH_CELLS, CLOTH_CELLS, (CLOTH_UV_REPEAT, -CLOTH_UV_REPEAT))
    # The floor in 16 x 16 cells (0.375 m, diagonals 0.53 m): its vertices carry the world light
    # (src/render/world_light.rs) near the balls and the cloth, every receiving triangle within a
    # quarter of the occlusion radius (0.3 of the scene's diagonal, 2.6 m), so the occlusion
    # pass's screen bounce adds nothing the vertices do not hold and the plan leaves it out.
    floor_mesh = grid_mesh(floor_quad, FLOOR_CELLS, FLOOR_CELLS, (6.0, -6.0))
    metal_centre = add(METAL_BALL_SPOT, [0.0, METAL_BALL_RADIUS, 0.0])
    check_clearances(cloth_mesh[0], metal_centre)

    materials = [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.3, 0.29, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9}},
        {"name": "ball", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.78, 0.74, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}},
        {
            "name": "red cloth",
            "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.045, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
            "doubleSided": True,
            "extensions": {
                "WEFT_materials_fabric": {
                    "pattern": "plain",
                    "repeat": 0.05,
                    "gap": 0.005,
                    "e_along": 200.0,
                    "e_across": 10.0,
                    "rd": [0.5, 0.045, 0.05],
                    "rs": 0.04,
                    "shadow_strength": 0.5,
                    "shadow_width": 0.25,
                }
            },
        },
        {"name": "polished steel", "pbrMetallicRoughness": {"baseColorFactor": [0.91, 0.9, 0.88, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.25}},
    ]

    ball_prim = b.primitive(ball, 1)
    metal_prim = dict(ball_prim, material=3)  # same geometry, another material
    meshes = [
        {"name": "floor", "primitives": [b.primitive(floor_mesh, 0)]},
        {"name": "ball", "primitives": [ball_prim]},
        {"name": "cloth", "primitives": [b.primitive(cloth_mesh, 2)]},
        {"name": "metal ball", "primitives": [metal_prim]},
    ]

    lights = [
        {"name": "key (warm sun)", "type": "directional", "color": [1.0, 0.9, 0.78], "intensity": 3.0},
        {"name": "fill (cool point)", "type": "point", "color": [0.8, 0.88, 1.0], "intensity": 5.0, "range": 12.0},
        {
            "name": "rim (spot)",
            "type": "spot",
            "color": [1.0, 0.96, 0.9],
            "intensity": 35.0,
            "range": 15.0,
            "spot": {"innerConeAngle": 0.22, "outerConeAngle": 0.42},
        },
    ]

    nodes = [
        {"name": "weft default scene", "children": [1, 2, 3, 4, 6, 7, 8, 9]},
        {"name": "floor", "mesh": 0},
        {"name": "ball", "mesh": 1, "translation": [r(c) for c in BALL_CENTER]},
        {"name": "cloth", "mesh": 2},
        # A parent node at the metal ball's spot on the floor; the ball itself is the unit-radius
        # mesh scaled and lifted in its child (exercises transform composition in loaders).
        {"name": "metal ball stand", "translation": [r(c) for c in METAL_BALL_SPOT], "children": [5]},
        {
            "name": "metal ball",
            "mesh": 3,
            "translation": [0.0, METAL_BALL_RADIUS, 0.0],
            "scale": [r(METAL_BALL_RADIUS / BALL_RADIUS)] * 3,
        },
        {"name": "key light", "translation": KEY_FROM, "rotation": look_rotation(KEY_FROM, [0.0, 0.0, 0.0]), "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "fill light", "translation": POINT_AT, "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "rim light", "translation": SPOT_AT, "rotation": look_rotation(SPOT_AT, SPOT_TARGET), "extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"name": "camera", "translation": CAMERA_EYE, "rotation": look_rotation(CAMERA_EYE, CAMERA_TARGET), "camera": 0},
    ]

    doc = {
        "asset": {"version": "2.0", "generator": "weft tools/make_default_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual", "WEFT_materials_fabric"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "draped cloth", "nodes": [0]}],
        "nodes": nodes,
        "cameras": [
            {
                "name": "front",
                "type": "perspective",
                "perspective": {"yfov": r(math.radians(40.0)), "aspectRatio": r(16.0 / 9.0), "znear": 0.05, "zfar": 50.0},
            }
        ],
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
    }
    while len(b.bin) % 4:
        b.bin.append(0)
    return doc, bytes(b.bin)


def write_glb(path, doc, binary):
    doc = dict(doc, buffers=[{"byteLength": len(binary)}])
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON"))
        f.write(text)
        f.write(struct.pack("<I4s", len(binary), b"BIN\0"))
        f.write(binary)


def write_gltf(path, doc, binary):
    bin_name = os.path.splitext(os.path.basename(path))[0] + ".bin"
    doc = dict(doc, buffers=[{"byteLength": len(binary), "uri": bin_name}])
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(json.dumps(doc, indent=1))
        f.write("\n")
    with open(os.path.join(os.path.dirname(path), bin_name), "wb") as f:
        f.write(binary)


def main():
    os.makedirs(ASSETS, exist_ok=True)
    doc, binary = build()
    write_glb(os.path.join(ASSETS, "default.glb"), doc, binary)
    write_gltf(os.path.join(ASSETS, "default.gltf"), doc, binary)
    for name in ("default.glb", "default.gltf", "default.bin"):
        print("wrote %s (%d bytes)" % (os.path.join(ASSETS, name), os.path.getsize(os.path.join(ASSETS, name))))


if __name__ == "__main__":
    main()
