#!/usr/bin/env python3
"""Writes the image-regression scenes: assets/scenes/*.glb (tests/regression.rs renders them).

Each scene stresses one thing (docs/regression.md has the list and what each golden should show):

  closeup       a gently curved plain-weave patch 10 cm from the camera: single threads resolved
  far           a rippled sheet 4 m away whose weave repeat (2 mm) is far below a pixel (~2 cm)
  grazing       a patch lit by a light 5 degrees above it; camera 0 looks across it at 7 degrees,
                camera 1 from above (the grazing light alone)
  many_lights   cloth, balls and a floor under 24 lights: 8 point, 8 spot, 8 directional
  twill_satin   a denim twill patch beside a satin one (pattern "twill" / "satin")
  mirrored_uv   the same twill twice, the right copy with u mirrored (tangent w = -1): the two
                halves of the image must be mirror images
  spheres       non-fabric glTF metallic-roughness: metallic 0 and 1 x roughness 0.05 .. 1
  shadows       a cloth under a ball and a floating box, lit by a directional and a spot light
                that ask for shadow maps (light "extras": {"shadows": ...}) and a point light that
                does not; one small ball does not cast (node "extras": {"cast_shadows": false})
  skinned_cloth a twill strip on a three-joint skin, bent up and twisted by a 2-second animation
                (a linear and a cubic-spline rotation channel): the thread directions must follow
                the bend (tests/animation.rs, goldens skinned-cloth-*)
  curtain       a sheer curtain (WEFT_materials_fabric "transmission": a single sheet) hanging in
                folds before a bright window and lit from behind by a low sun; camera 0 the whole
                curtain from the room (weave below a pixel), camera 1 a close-up (threads and gaps
                resolved)
  gltf_core     glTF core features of issue 25: a triangle strip and fan, COLOR_0, an unlit
                sphere, an alphaMode MASK card with cut-out holes (and their shadow), nine
                EXT_mesh_gpu_instancing cubes; camera 1 orthographic (goldens gltf-core-*)

Python 3 standard library only; the output is byte-for-byte deterministic. The geometry helpers
and the glTF writer are those of tools/make_default_scene.py (imported). Y is up, units are
metres. Run from anywhere:  python3 tools/make_scenes.py
"""

import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import make_default_scene as base  # noqa: E402  (the shared helpers: grid_mesh, Builder, write_glb, ...)
from make_default_scene import Builder, grid_mesh, look_rotation, r, write_glb  # noqa: E402

OUT = os.path.join(os.path.dirname(HERE), "assets", "scenes")
ASPECT = 16.0 / 9.0

# --- shared pieces --------------------------------------------------------------------------------


def fabric(name, pattern="plain", repeat=0.05, gap=0.005, rd=None, rd_warp=None, rd_weft=None, rs=0.04,
           e_along=200.0, e_across=10.0, base_color=(0.5, 0.5, 0.5)):
    ext = {"pattern": pattern, "repeat": repeat, "gap": gap, "e_along": e_along, "e_across": e_across, "rs": rs,
           "shadow_strength": 0.5, "shadow_width": 0.25}
    if rd is not None:
        ext["rd"] = list(rd)
    if rd_warp is not None:
        ext["rd_warp"] = list(rd_warp)
    if rd_weft is not None:
        ext["rd_weft"] = list(rd_weft)
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": list(base_color) + [1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8},
        "doubleSided": True,
        "extensions": {"WEFT_materials_fabric": ext},
    }


def pbr(name, color, metallic, roughness):
    return {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(color) + [1.0], "metallicFactor": metallic,
                                                   "roughnessFactor": roughness}}


def patch(x0, x1, z0, z1, y=lambda x, z: 0.0, uv_per_m=1.0, mirror_u=False):
    """A patch of the plane y = y(x, z) over [x0, x1] x [z0, z1], facing +Y. Texture u runs along +x
    (along -x with mirror_u: the tangent then points -x and its w is -1), v along -z (so that
    w = +1 for the unmirrored patch), uv = metres * uv_per_m, starting at 0."""

    def f(u, v):
        x = x1 + (x0 - x1) * u if mirror_u else x0 + (x1 - x0) * u
        z = z1 + (z0 - z1) * v
        return [x, y(x, z), z]

    def normal(u, v):
        p = f(u, v)
        e = 1e-4
        dydx = (y(p[0] + e, p[2]) - y(p[0] - e, p[2])) / (2 * e)
        dydz = (y(p[0], p[2] + e) - y(p[0], p[2] - e)) / (2 * e)
        return base.normalize([-dydx, 1.0, -dydz])

    return f, normal, ((x1 - x0) * uv_per_m, (z1 - z0) * uv_per_m)


def patch_mesh(x0, x1, z0, z1, nu, nv, **kw):
    f, normal, uv_scale = patch(x0, x1, z0, z1, **kw)
    return grid_mesh(f, nu, nv, uv_scale, normal_fn=normal)


def unit_sphere(u, v):
    theta, phi = v * math.pi, u * 2.0 * math.pi
    return [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]


def unit_sphere_normal(u, v):
    return base.normalize(unit_sphere(u, v)) if 0.0 < v < 1.0 else [0.0, 1.0 if v < 0.5 else -1.0, 0.0]


def sphere_mesh(nu=32, nv=16):
    return grid_mesh(unit_sphere, nu, nv, (1.0, 1.0), normal_fn=unit_sphere_normal, v_clamp=0.02)


def box_mesh(half):
    """A cube of half-size `half` centred on the origin: six flat faces of one quad each, with
    their own normals, tangents and texture coordinates (0..1 per face)."""
    faces = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            # Two in-face axes a, b with cross(a, b) = n.
            a = [0.0, 0.0, 0.0]
            a[(axis + 1) % 3] = 1.0
            b = base.cross(n, a)

            def f(u, v, n=n, a=a, b=b):
                return [half * (n[k] + (2.0 * u - 1.0) * a[k] + (2.0 * v - 1.0) * b[k]) for k in range(3)]

            faces.append(grid_mesh(f, 1, 1, (1.0, 1.0), normal_fn=lambda u, v, n=n: list(n)))
    pos, nrm, tan, uvs, idx = [], [], [], [], []
    for fp, fn, ft, fu, fi in faces:
        idx += [len(pos) + i for i in fi]
        pos += fp
        nrm += fn
        tan += ft
        uvs += fu
    return pos, nrm, tan, uvs, idx


def camera_node(name, eye, target, index):
    return {"name": name, "translation": [r(c) for c in eye], "rotation": look_rotation(eye, target), "camera": index}


def camera_def(name, yfov_deg, znear):
    return {"name": name, "type": "perspective",
            "perspective": {"yfov": r(math.radians(yfov_deg)), "aspectRatio": r(ASPECT), "znear": znear, "zfar": 100.0}}


def light_node(name, index, at, target=None):
    node = {"name": name, "translation": [r(c) for c in at], "extensions": {"KHR_lights_punctual": {"light": index}}}
    if target is not None:
        node["rotation"] = look_rotation(at, target)
    return node


def directional(name, color, intensity):
    return {"name": name, "type": "directional", "color": [r(c) for c in color], "intensity": r(intensity)}


def point(name, color, intensity, rng=10.0):
    return {"name": name, "type": "point", "color": [r(c) for c in color], "intensity": r(intensity), "range": rng}


def spot(name, color, intensity, inner, outer, rng=10.0):
    return {"name": name, "type": "spot", "color": [r(c) for c in color], "intensity": r(intensity), "range": rng,
            "spot": {"innerConeAngle": r(inner), "outerConeAngle": r(outer)}}


def document(name, b, materials, meshes, nodes, lights, cameras):
    """The glTF document: one root node whose children are `nodes` (flat: no node has children)."""
    doc = {
        "asset": {"version": "2.0", "generator": "weft tools/make_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual", "WEFT_materials_fabric"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": name, "nodes": [0]}],
        "nodes": [{"name": name, "children": list(range(1, len(nodes) + 1))}] + nodes,
        "cameras": cameras,
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
    }
    if not any("WEFT_materials_fabric" in m.get("extensions", {}) for m in materials):
        doc["extensionsUsed"] = ["KHR_lights_punctual"]
    while len(b.bin) % 4:
        b.bin.append(0)
    return doc, bytes(b.bin)


# --- the scenes -----------------------------------------------------------------------------------


def closeup():
    """A 28 cm x 22 cm plain-weave patch, bent along x with a 1 m radius, seen from 10 cm (it fills
    the view).
    Texture: 10 units per metre, repeat 0.08 units = 8 mm, so a repeat is ~16 px at 144 px height
    and a cell ~8 px; the gap (10 % of the repeat, 4 % of the area) is ~1 px wide."""
    b = Builder()
    bend = 1.0
    mesh = patch_mesh(-0.14, 0.14, -0.16, 0.06, 24, 20, y=lambda x, z: -x * x / (2.0 * bend), uv_per_m=10.0)
    materials = [fabric("two-colour plain weave", repeat=0.08, gap=0.008, rd_warp=(0.55, 0.10, 0.07),
                        rd_weft=(0.62, 0.46, 0.12), base_color=(0.6, 0.3, 0.1))]
    meshes = [{"name": "patch", "primitives": [b.primitive(mesh, 0)]}]
    lights = [directional("key", (1.0, 0.95, 0.9), 2.5), point("near point", (0.9, 0.95, 1.0), 0.08, rng=2.0)]
    nodes = [
        {"name": "patch", "mesh": 0},
        light_node("key", 0, [0.3, 0.6, 0.5], [0.0, 0.0, 0.0]),
        light_node("near point", 1, [-0.03, 0.06, 0.02]),
        camera_node("10 cm", [0.0, 0.075, 0.066], [0.0, 0.0, 0.0], 0),
    ]
    return document("close-up", b, materials, meshes, nodes, lights, [camera_def("10 cm", 40.0, 0.01)])


def far():
    """A 3 m x 3 m sheet with ripples along z (so highlights move over it) seen from 3.5 m. Texture:
    one unit per metre, repeat 0.002 = 2 mm, while a pixel covers ~2 cm: ten repeats and more per
    pixel, more at the far edge. Only the repeat-averaged coverage should be visible."""
    b = Builder()
    mesh = patch_mesh(-1.5, 1.5, -1.5, 1.5, 12, 48, y=lambda x, z: 0.06 * math.sin(2.0 * math.pi * z / 0.6), uv_per_m=1.0)
    materials = [fabric("fine blue weave", repeat=0.002, gap=0.0002, rd=(0.10, 0.22, 0.55), e_along=300.0, e_across=8.0,
                        base_color=(0.1, 0.2, 0.5))]
    meshes = [{"name": "sheet", "primitives": [b.primitive(mesh, 0)]}]
    lights = [directional("key", (1.0, 0.93, 0.85), 3.0), point("fill", (0.8, 0.9, 1.0), 6.0, rng=12.0)]
    nodes = [
        {"name": "sheet", "mesh": 0},
        light_node("key", 0, [-1.0, 2.0, -3.0], [0.0, 0.0, 0.0]),
        light_node("fill", 1, [1.5, 1.2, 1.5]),
        camera_node("3.5 m", [0.0, 1.6, 2.6], [0.0, -0.1, -0.3], 0),
    ]
    return document("far view", b, materials, meshes, nodes, lights, [camera_def("3.5 m", 40.0, 0.1)])


def grazing():
    """A 1 m x 2 m plain weave (2 cm repeat) under a directional light 5 degrees above its plane,
    from behind and to the side, so that the cloth's forward-scattering sheen faces the camera.
    Camera 0: 7 degrees above the plane, looking across it (resolved weave in front, minified far
    below a pixel behind); camera 1: from 60 degrees above (the grazing light alone)."""
    b = Builder()
    mesh = patch_mesh(-0.5, 0.5, -1.5, 0.5, 8, 16, uv_per_m=1.0)
    materials = [fabric("grey plain weave", repeat=0.02, gap=0.002, rd=(0.45, 0.45, 0.42), e_along=200.0, e_across=10.0,
                        base_color=(0.45, 0.45, 0.42))]
    meshes = [{"name": "patch", "primitives": [b.primitive(mesh, 0)]}]
    elevation = math.radians(5.0)
    side = math.radians(20.0)  # from behind (-z), turned 20 degrees toward +x
    light_from = [math.cos(elevation) * math.sin(side), math.sin(elevation), -math.cos(elevation) * math.cos(side)]
    lights = [directional("grazing sun", (1.0, 0.9, 0.75), 15.0)]
    view_el = math.radians(7.0)
    nodes = [
        {"name": "patch", "mesh": 0},
        light_node("grazing sun", 0, base.scale(light_from, 3.0), [0.0, 0.0, 0.0]),
        camera_node("grazing view", [0.0, 0.9 * math.tan(view_el), 0.4], [0.0, 0.0, -0.5], 0),
        camera_node("from above", [0.0, 1.5, 0.5], [0.0, 0.0, -0.4], 1),
    ]
    cams = [camera_def("grazing view", 40.0, 0.01), camera_def("from above", 45.0, 0.05)]
    return document("grazing", b, materials, meshes, nodes, lights, cams)


def hue(h):
    """A saturated colour of hue h in [0, 1)."""
    k = [(5.0 + h * 6.0) % 6.0, (3.0 + h * 6.0) % 6.0, (1.0 + h * 6.0) % 6.0]
    return [1.0 - 0.75 * max(0.0, min(k_, 4.0 - k_, 1.0)) for k_ in k]


def many_lights():
    """A rippled cloth, two balls and a floor under 24 lights: 8 coloured points in a ring, 8 spots
    from above aimed at the centre, 8 weak directional lights from all around."""
    b = Builder()
    cloth = patch_mesh(-0.7, 0.7, -0.7, 0.7, 24, 24, y=lambda x, z: 0.25 + 0.04 * math.sin(5.0 * x) * math.cos(4.0 * z),
                       uv_per_m=1.0)
    floor = patch_mesh(-3.0, 3.0, -3.0, 3.0, 1, 1, uv_per_m=1.0)
    ball = sphere_mesh()
    materials = [
        fabric("white plain weave", repeat=0.03, gap=0.003, rd=(0.6, 0.6, 0.6), base_color=(0.6, 0.6, 0.6)),
        pbr("floor", (0.3, 0.3, 0.3), 0.0, 0.8),
        pbr("plastic", (0.7, 0.7, 0.7), 0.0, 0.35),
        pbr("chrome", (0.95, 0.95, 0.95), 1.0, 0.15),
    ]
    ball_prim = b.primitive(ball, 2)
    meshes = [
        {"name": "cloth", "primitives": [b.primitive(cloth, 0)]},
        {"name": "floor", "primitives": [b.primitive(floor, 1)]},
        {"name": "plastic ball", "primitives": [ball_prim]},
        {"name": "chrome ball", "primitives": [dict(ball_prim, material=3)]},
    ]
    lights, nodes = [], [
        {"name": "cloth", "mesh": 0},
        {"name": "floor", "mesh": 1},
        {"name": "plastic ball", "mesh": 2, "translation": [-0.95, 0.2, 0.55], "scale": [0.2, 0.2, 0.2]},
        {"name": "chrome ball", "mesh": 3, "translation": [0.95, 0.2, 0.55], "scale": [0.2, 0.2, 0.2]},
    ]
    for i in range(8):
        a = 2.0 * math.pi * i / 8.0
        lights.append(point("point %d" % i, hue(i / 8.0), 0.9, rng=4.0))
        nodes.append(light_node("point %d" % i, len(lights) - 1, [1.2 * math.cos(a), 0.5, 1.2 * math.sin(a)]))
    for i in range(8):
        a = 2.0 * math.pi * (i + 0.5) / 8.0
        at = [1.6 * math.cos(a), 2.2, 1.6 * math.sin(a)]
        lights.append(spot("spot %d" % i, hue((i + 0.5) / 8.0), 6.0, 0.12, 0.3, rng=8.0))
        nodes.append(light_node("spot %d" % i, len(lights) - 1, at, [0.35 * math.cos(a), 0.25, 0.35 * math.sin(a)]))
    for i in range(8):
        a = 2.0 * math.pi * i / 8.0 + 0.3
        el = math.radians(15.0 + 10.0 * (i % 4))
        frm = [math.cos(a) * math.cos(el), math.sin(el), math.sin(a) * math.cos(el)]
        lights.append(directional("sun %d" % i, hue((i + 0.25) / 8.0), 0.12))
        nodes.append(light_node("sun %d" % i, len(lights) - 1, base.scale(frm, 5.0), [0.0, 0.0, 0.0]))
    nodes.append(camera_node("front", [0.0, 1.7, 2.6], [0.0, 0.2, 0.0], 0))
    return document("many lights", b, materials, meshes, nodes, lights, [camera_def("front", 40.0, 0.05)])


def twill_satin():
    """Denim (3/1 twill, indigo warp, white weft) beside a red and gold 5-harness satin, both 14 cm
    square, seen from 28 cm. Texture: 10 units per metre, repeat 0.12 = 12 mm (cells of 6 mm,
    ~5 px at 144 px height), so the twill's diagonal and the satin's scattered weft dots show."""
    b = Builder()
    left = patch_mesh(-0.15, -0.01, -0.07, 0.07, 8, 8, uv_per_m=10.0)
    right = patch_mesh(0.01, 0.15, -0.07, 0.07, 8, 8, uv_per_m=10.0)
    materials = [
        fabric("denim twill", pattern="twill", repeat=0.12, gap=0.01, rd_warp=(0.06, 0.10, 0.32), rd_weft=(0.75, 0.74, 0.70),
               e_along=150.0, e_across=8.0, base_color=(0.1, 0.15, 0.35)),
        fabric("satin", pattern="satin", repeat=0.12, gap=0.006, rd_warp=(0.70, 0.52, 0.12), rd_weft=(0.45, 0.04, 0.05),
               rs=0.06, e_along=600.0, e_across=20.0, base_color=(0.6, 0.4, 0.1)),
    ]
    meshes = [{"name": "twill", "primitives": [b.primitive(left, 0)]},
              {"name": "satin", "primitives": [b.primitive(right, 1)]}]
    lights = [directional("key", (1.0, 0.95, 0.9), 3.0), point("fill", (0.85, 0.9, 1.0), 0.3, rng=3.0)]
    nodes = [
        {"name": "twill", "mesh": 0},
        {"name": "satin", "mesh": 1},
        light_node("key", 0, [0.2, 0.5, 0.6], [0.0, 0.0, 0.0]),
        light_node("fill", 1, [-0.1, 0.2, 0.15]),
        camera_node("front", [0.0, 0.22, 0.17], [0.0, 0.0, 0.0], 0),
    ]
    return document("twill and satin", b, materials, meshes, nodes, lights, [camera_def("front", 40.0, 0.02)])


def mirrored_uv():
    """The same twill twice, left with u along +x (tangent w = +1), right with u along -x (tangent
    w = -1). Camera and lights lie in the plane x = 0, so the right half must be the mirror image
    of the left, the twill's diagonal included."""
    b = Builder()
    left = patch_mesh(-0.15, -0.005, -0.07, 0.07, 8, 8, uv_per_m=10.0)
    right = patch_mesh(0.005, 0.15, -0.07, 0.07, 8, 8, uv_per_m=10.0, mirror_u=True)
    assert all(t[3] == 1.0 for t in left[2]) and all(t[3] == -1.0 for t in right[2])
    materials = [fabric("green twill", pattern="twill", repeat=0.12, gap=0.01, rd_warp=(0.08, 0.35, 0.12),
                        rd_weft=(0.70, 0.66, 0.50), e_along=200.0, e_across=10.0, base_color=(0.1, 0.35, 0.15))]
    meshes = [{"name": "u along +x", "primitives": [b.primitive(left, 0)]},
              {"name": "u along -x (mirrored, w = -1)", "primitives": [b.primitive(right, 0)]}]
    lights = [directional("key", (1.0, 0.95, 0.9), 3.0), point("near", (0.9, 0.95, 1.0), 0.25, rng=3.0)]
    nodes = [
        {"name": "left", "mesh": 0},
        {"name": "right (mirrored)", "mesh": 1},
        light_node("key", 0, [0.0, 0.5, 0.6], [0.0, 0.0, 0.0]),
        light_node("near", 1, [0.0, 0.12, -0.05]),
        camera_node("front", [0.0, 0.22, 0.17], [0.0, 0.0, 0.0], 0),
    ]
    return document("mirrored uv", b, materials, meshes, nodes, lights, [camera_def("front", 40.0, 0.02)])


ROUGHNESS = [0.05, 0.25, 0.5, 0.75, 1.0]


def spheres():
    """Ten balls of radius 0.2 m on a dark floor: back row metallic 1 (gold), front row metallic 0
    (red plastic), roughness 0.05, 0.25, 0.5, 0.75, 1 from left to right. One sphere geometry."""
    b = Builder()
    ball = sphere_mesh()
    floor = patch_mesh(-4.0, 4.0, -4.0, 4.0, 1, 1, uv_per_m=1.0)
    materials = [pbr("floor", (0.18, 0.18, 0.2), 0.0, 0.9)]
    for m, color in ((1.0, (1.0, 0.78, 0.34)), (0.0, (0.8, 0.12, 0.08))):
        for rough in ROUGHNESS:
            materials.append(pbr("metallic %g roughness %g" % (m, rough), color, m, rough))
    ball_prim = b.primitive(ball, 1)
    meshes = [{"name": "floor", "primitives": [b.primitive(floor, 0)]}]
    nodes = [{"name": "floor", "mesh": 0}]
    for k in range(10):
        meshes.append({"name": materials[k + 1]["name"], "primitives": [dict(ball_prim, material=k + 1)]})
        row, col = divmod(k, 5)
        nodes.append({"name": materials[k + 1]["name"], "mesh": k + 1,
                      "translation": [r(-1.0 + 0.5 * col), 0.2, r(-0.45 + 0.65 * row)], "scale": [0.2, 0.2, 0.2]})
    lights = [directional("key", (1.0, 0.96, 0.9), 3.0), point("fill", (0.8, 0.88, 1.0), 3.0, rng=10.0)]
    nodes += [
        light_node("key", 0, [1.0, 2.0, 1.5], [0.0, 0.0, 0.0]),
        light_node("fill", 1, [-1.5, 1.0, 1.5]),
        camera_node("front", [0.0, 1.7, 2.3], [0.0, 0.05, -0.1], 0),
    ]
    return document("metallic-roughness spheres", b, materials, meshes, nodes, lights, [camera_def("front", 35.0, 0.05)])


SUN_ELEVATION = math.radians(40.0)
SUN_AZIMUTH = math.radians(-140.0)  # from behind the objects, on the left as the camera sees them


def shadows():
    """A 3 m x 3 m plain-weave cloth on the ground (y = 0) with a red plastic ball resting on it, a
    grey box floating 12 cm above it and, in front, a small ball that casts no shadow: its node's
    parent has "extras": {"cast_shadows": false}, which the ball inherits. Lights: a sun 40 degrees
    above the cloth with "extras": {"shadows": true} (the default shadow map), a spot from above
    aimed down at the cloth between the objects with {"resolution": 512, "filter_radius": 2.5}, and
    a weak point light without shadows. The camera looks at the group from a 3/4 view above."""
    b = Builder()
    cloth = patch_mesh(-1.5, 1.5, -1.5, 1.5, 16, 16, uv_per_m=1.0)
    ball = sphere_mesh()
    box = box_mesh(0.2)
    materials = [
        fabric("sand plain weave", repeat=0.03, gap=0.003, rd=(0.62, 0.55, 0.42), base_color=(0.62, 0.55, 0.42)),
        pbr("red plastic", (0.8, 0.12, 0.08), 0.0, 0.35),
        pbr("grey box", (0.5, 0.5, 0.52), 0.0, 0.6),
        pbr("brushed steel", (0.9, 0.9, 0.92), 1.0, 0.3),
    ]
    meshes = [
        {"name": "cloth", "primitives": [b.primitive(cloth, 0)]},
        {"name": "ball", "primitives": [b.primitive(ball, 1)]},
        {"name": "box", "primitives": [b.primitive(box, 2)]},
    ]
    meshes.append({"name": "small ball", "primitives": [dict(meshes[1]["primitives"][0], material=3)]})
    elevation, azimuth = SUN_ELEVATION, SUN_AZIMUTH
    sun_from = [math.cos(elevation) * math.cos(azimuth), math.sin(elevation), math.cos(elevation) * math.sin(azimuth)]
    sun = directional("sun", (1.0, 0.95, 0.88), 2.5)
    sun["extras"] = {"shadows": True}
    lamp = spot("spot", (1.0, 0.9, 0.75), 12.0, 0.3, 0.5, rng=10.0)
    lamp["extras"] = {"shadows": {"resolution": 512, "filter_radius": 2.5}}
    lights = [sun, lamp, point("fill", (0.8, 0.88, 1.0), 0.6, rng=8.0)]
    ball_radius = 0.3
    nodes = [
        {"name": "cloth", "mesh": 0},
        {"name": "ball", "mesh": 1, "translation": [-0.45, r(ball_radius + 0.005), 0.1], "scale": [ball_radius] * 3},
        # The box floats: its shadow must stay detached from it (no peter-panning hides the gap).
        {"name": "floating box", "mesh": 2, "translation": [0.45, 0.32, -0.25],
         "rotation": [0.0, r(math.sin(math.radians(15.0))), 0.0, r(math.cos(math.radians(15.0)))]},
        # Its child (appended below) is the small ball: it inherits cast_shadows = false.
        {"name": "no shadow caster", "translation": [0.3, 0.0, 0.65], "extras": {"cast_shadows": False}},
        light_node("sun", 0, base.scale(sun_from, 5.0), [0.0, 0.0, 0.0]),
        light_node("spot", 1, [0.25, 2.4, 0.45], [0.05, 0.0, 0.1]),
        light_node("fill", 2, [-1.4, 1.2, 1.6]),
        camera_node("3/4 view", [1.5, 1.15, 1.8], [0.0, 0.12, 0.05], 0),
    ]
    doc, binary = document("shadows", b, materials, meshes, nodes, lights, [camera_def("3/4 view", 40.0, 0.05)])
    small = 0.08
    doc["nodes"].append({"name": "small ball", "mesh": 3, "translation": [0.0, r(small + 0.002), 0.0], "scale": [small] * 3})
    doc["nodes"][4]["children"] = [len(doc["nodes"]) - 1]
    return doc, binary


def skinned_cloth():
    """A 1.4 m x 0.4 m denim twill strip along x (y = 0, facing +Y) on a chain of three joints at
    x = -0.6, 0 and 0.4. Each vertex blends its joints by smoothsteps of x around the inner joints
    (weights sum to 1). Animation "bend" (2 s): the middle joint turns about z by 0, 50, 20 degrees
    at t = 0, 1, 2 (linear), the last about x by 0, 40, 70 degrees (cubic spline, zero tangents):
    the strip bends up at x = 0 and its end twists."""
    b = Builder()
    mesh = patch_mesh(-0.6, 0.8, -0.2, 0.2, 56, 8, uv_per_m=10.0)
    pos = mesh[0]
    joints_x = [-0.6, 0.0, 0.4]

    def smooth(e0, e1, x):
        t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
        return t * t * (3.0 - 2.0 * t)

    weights = []
    for p in pos:
        w1 = smooth(-0.1, 0.1, p[0])
        w2 = smooth(0.3, 0.5, p[0])
        weights.append([r(1.0 - w1), r(w1 * (1.0 - w2)), r(w1 * w2), 0.0])
    prim = b.primitive(mesh, 0)
    joints_data = b"".join(struct.pack("<4H", 0, 1, 2, 0) for _ in pos)
    b.accessors.append({"bufferView": b._view(joints_data, 34962), "componentType": 5123, "count": len(pos),
                        "type": "VEC4"})
    prim["attributes"]["JOINTS_0"] = len(b.accessors) - 1
    prim["attributes"]["WEIGHTS_0"] = b.floats(weights, "VEC4")
    # Inverse bind matrices: the joints' bind poses are translations along x (column-major).
    ibm = [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -x, 0, 0, 1] for x in joints_x]
    ibm_acc = b.floats(ibm, "MAT4")

    def quat(axis, deg):
        h = math.radians(deg) / 2.0
        q = [0.0, 0.0, 0.0, r(math.cos(h))]
        q["xyz".index(axis)] = r(math.sin(h))
        return q

    times = b.floats([[0.0], [1.0], [2.0]], "SCALAR", with_bounds=True)
    bend = b.floats([quat("z", d) for d in (0.0, 50.0, 20.0)], "VEC4")
    zero = [0.0, 0.0, 0.0, 0.0]
    twist = b.floats([row for d in (0.0, 40.0, 70.0) for row in (zero, quat("x", d), zero)], "VEC4")
    materials = [fabric("skinned denim", pattern="twill", repeat=0.1, gap=0.006, rd_warp=(0.10, 0.16, 0.36),
                        rd_weft=(0.62, 0.60, 0.55), base_color=(0.2, 0.25, 0.4))]
    meshes = [{"name": "strip", "primitives": [prim]}]
    lights = [directional("key", (1.0, 0.95, 0.9), 3.0)]
    nodes = [
        {"name": "skinned cloth", "children": [1, 2, 5, 6]},
        {"name": "strip", "mesh": 0, "skin": 0},
        {"name": "joint 0", "translation": [joints_x[0], 0.0, 0.0], "children": [3]},
        {"name": "joint 1", "translation": [joints_x[1] - joints_x[0], 0.0, 0.0], "children": [4]},
        {"name": "joint 2", "translation": [joints_x[2] - joints_x[1], 0.0, 0.0]},
        light_node("key", 0, [0.5, 1.5, 1.0], [0.0, 0.0, 0.0]),
        camera_node("front", [0.1, 1.0, 1.8], [0.1, 0.3, 0.0], 0),
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "weft tools/make_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual", "WEFT_materials_fabric"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "skinned cloth", "nodes": [0]}],
        "nodes": nodes,
        "skins": [{"name": "chain", "joints": [2, 3, 4], "inverseBindMatrices": ibm_acc, "skeleton": 2}],
        "animations": [{"name": "bend", "channels": [
            {"sampler": 0, "target": {"node": 3, "path": "rotation"}},
            {"sampler": 1, "target": {"node": 4, "path": "rotation"}},
        ], "samplers": [
            {"input": times, "output": bend, "interpolation": "LINEAR"},
            {"input": times, "output": twist, "interpolation": "CUBICSPLINE"},
        ]}],
        "cameras": [camera_def("front", 40.0, 0.05)],
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
    }
    while len(b.bin) % 4:
        b.bin.append(0)
    return doc, bytes(b.bin)


def gltf_core():
    """glTF 2.0 core features weft used to ignore, one object each, on a grey floor under a sun
    with a shadow map (issue 25): from left to right a blue ribbon written as a TRIANGLE_STRIP
    (non-indexed) above an orange hexagon written as a TRIANGLE_FAN (indexed), a cube whose
    faces are coloured by COLOR_0 (normalized unsigned bytes, VEC4) over a white material, a
    green KHR_materials_unlit sphere (flat, no shading), a white card with alphaMode MASK whose
    COLOR_0 alpha cuts out a grid of round holes (the holes show in its shadow too), and nine
    small cubes placed by one node with EXT_mesh_gpu_instancing (a 3 x 3 grid, each turned and
    scaled). Camera 0: perspective 3/4 view; camera 1: orthographic from the front (xmag 2.4,
    ymag 1.35)."""
    b = Builder()
    floor = patch_mesh(-2.5, 2.5, -1.5, 1.5, 1, 1)
    materials = [
        pbr("grey floor", (0.5, 0.5, 0.5), 0.0, 0.8),
        pbr("blue", (0.1, 0.25, 0.8), 0.0, 0.5),
        pbr("orange", (0.9, 0.4, 0.05), 0.0, 0.5),
        pbr("white", (1.0, 1.0, 1.0), 0.0, 0.5),
        dict(pbr("unlit green", (0.2, 0.7, 0.3), 0.0, 0.5), extensions={"KHR_materials_unlit": {}}),
        dict(pbr("lace card", (0.95, 0.92, 0.85), 0.0, 0.7), alphaMode="MASK", alphaCutoff=0.5, doubleSided=True),
        pbr("brass", (0.9, 0.7, 0.3), 0.0, 0.35),
    ]
    meshes = [{"name": "floor", "primitives": [b.primitive(floor, 0)]}]

    # A ribbon of three quads standing in z = 0 as a triangle strip of 8 vertices, zig-zagging
    # top, bottom, top, ...: the first triangle counter-clockwise seen from +z.
    strip = []
    for k in range(4):
        x = -2.1 + 0.2 * k
        strip += [[x, 0.85, 0.0], [x, 0.55, 0.0]]
    meshes.append({"name": "ribbon (TRIANGLE_STRIP)", "primitives": [{
        "attributes": {"POSITION": b.floats(strip, "VEC3", with_bounds=True),
                       "NORMAL": b.floats([[0.0, 0.0, 1.0]] * len(strip), "VEC3")},
        "material": 1, "mode": 5}]})
    # A hexagon in z = 0: centre, then the ring counter-clockwise and closed, as an indexed fan.
    ring = [[-1.8 + 0.25 * math.cos(a * math.pi / 3), 0.28 + 0.25 * math.sin(a * math.pi / 3), 0.0] for a in range(6)]
    hexagon = [[-1.8, 0.28, 0.0]] + ring
    meshes.append({"name": "hexagon (TRIANGLE_FAN)", "primitives": [{
        "attributes": {"POSITION": b.floats(hexagon, "VEC3", with_bounds=True),
                       "NORMAL": b.floats([[0.0, 0.0, 1.0]] * len(hexagon), "VEC3")},
        "indices": b.indices([0, 1, 2, 3, 4, 5, 6, 1]), "material": 2, "mode": 6}]})

    # A cube with its faces coloured by COLOR_0 as normalized unsigned bytes.
    cube = box_mesh(0.25)
    prim = b.primitive(cube, 3)
    colours = []
    for n in cube[1]:
        c = [int(round(255 * (0.5 + 0.5 * x))) for x in n]
        colours.append(c + [255])
    view = b._view(bytes(v for c in colours for v in c), 34962)
    b.accessors.append({"bufferView": view, "componentType": 5121, "normalized": True, "count": len(colours), "type": "VEC4"})
    prim["attributes"]["COLOR_0"] = len(b.accessors) - 1
    meshes.append({"name": "coloured cube (COLOR_0)", "primitives": [prim]})

    meshes.append({"name": "unlit sphere", "primitives": [b.primitive(sphere_mesh(), 4)]})

    # The card: a 24 x 24 grid in z = 0 whose COLOR_0 alpha is 0 inside a 4 x 4 grid of round
    # holes (float VEC4): cut out where the interpolated alpha is below 0.5.
    n = 24
    card = grid_mesh(lambda u, v: [0.85 + 0.8 * u, 0.2 + 0.8 * (1.0 - v), 0.0], n, n, (1.0, 1.0),
                     normal_fn=lambda u, v: [0.0, 0.0, 1.0])
    prim = b.primitive(card, 5)
    alphas = []
    for j in range(n + 1):
        for i in range(n + 1):
            u, v = i / n, j / n
            cu, cv = (u * 4) % 1.0 - 0.5, (v * 4) % 1.0 - 0.5
            alphas.append([1.0, 1.0, 1.0, 0.0 if cu * cu + cv * cv < 0.09 else 1.0])
    prim["attributes"]["COLOR_0"] = b.floats(alphas, "VEC4")
    meshes.append({"name": "lace card (alphaMode MASK)", "primitives": [prim]})

    meshes.append({"name": "small cube", "primitives": [b.primitive(box_mesh(0.07), 6)]})
    translations, rotations, scales = [], [], []
    for k in range(9):
        i, j = k % 3, k // 3
        translations.append([0.22 * (i - 1), 0.0, 0.22 * (j - 1)])
        a = math.radians(15.0 * k) / 2.0
        rotations.append([0.0, r(math.sin(a)), 0.0, r(math.cos(a))])
        s = 0.7 + 0.1 * k / 2.0
        scales.append([s, s, s])

    sun = directional("sun", (1.0, 0.96, 0.9), 3.0)
    sun["extras"] = {"shadows": {"resolution": 1024}}
    lights = [sun]
    sun_from = [0.45, 0.8, 0.55]
    nodes = [
        {"name": "floor", "mesh": 0},
        {"name": "ribbon", "mesh": 1},
        {"name": "hexagon", "mesh": 2},
        {"name": "coloured cube", "mesh": 3, "translation": [-0.85, 0.25, 0.0],
         "rotation": [0.0, r(math.sin(math.radians(20.0))), 0.0, r(math.cos(math.radians(20.0)))]},
        {"name": "unlit sphere", "mesh": 4, "translation": [0.25, 0.3, 0.0], "scale": [0.3] * 3},
        {"name": "lace card", "mesh": 5, "translation": [0.0, 0.0, -0.3]},
        {"name": "instanced cubes", "mesh": 6, "translation": [2.0, 0.08, 0.2],
         "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {
             "TRANSLATION": b.floats(translations, "VEC3"),
             "ROTATION": b.floats(rotations, "VEC4"),
             "SCALE": b.floats(scales, "VEC3")}}}},
        light_node("sun", 0, base.scale(sun_from, 5.0), [0.0, 0.0, 0.0]),
        camera_node("3/4 view", [0.4, 2.0, 3.6], [0.1, 0.35, 0.0], 0),
        {"name": "front (orthographic)", "translation": [0.0, 0.55, 5.0], "camera": 1},
    ]
    cameras = [
        camera_def("3/4 view", 45.0, 0.05),
        {"name": "front (orthographic)", "type": "orthographic",
         "orthographic": {"xmag": r(1.35 * ASPECT), "ymag": 1.35, "znear": 0.05, "zfar": 20.0}},
    ]
    doc, binary = document("gltf_core", b, materials, meshes, nodes, lights, cameras)
    doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_unlit", "EXT_mesh_gpu_instancing"]
    return doc, binary


def curtain():
    """A 2 m x 2 m voile (plain weave, 4 mm repeat, wide gaps) hanging in folds 5 cm deep at z = 0,
    facing the room (+z); 60 cm behind it a window, an emissive panel (radiance 1); a directional
    sun from behind and above the window shining through the curtain into the room; a dim point
    light on the room side. The curtain is a single sheet: its gaps show the window, its threads
    pass 0.4 of their diffuse light (the sun from behind)."""
    b = Builder()
    fold = lambda x, z: 0.05 * math.sin(2.0 * math.pi * x / 0.4)
    # Horizontal patches turned upright by a quarter turn about +x (+y to +z): (x, y, z) -> (x, -z, y).
    upright = [r(math.sin(math.radians(45.0))), 0.0, 0.0, r(math.cos(math.radians(45.0)))]
    sheet = patch_mesh(-1.0, 1.0, -2.2, -0.2, 48, 24, y=fold, uv_per_m=1.0)
    window = patch_mesh(-1.4, 1.4, -2.6, 0.0, 2, 2)
    voile = fabric("voile", repeat=0.004, gap=0.0007, rd_warp=(0.80, 0.76, 0.66), rd_weft=(0.74, 0.70, 0.62),
                   e_along=300.0, e_across=12.0, base_color=(0.78, 0.74, 0.64))
    voile["extensions"]["WEFT_materials_fabric"]["transmission"] = 0.4
    window_mat = {"name": "window", "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0],
                                                             "metallicFactor": 0.0, "roughnessFactor": 1.0},
                  "emissiveFactor": [1.0, 0.97, 0.9]}
    materials = [voile, window_mat]
    meshes = [{"name": "curtain", "primitives": [b.primitive(sheet, 0)]},
              {"name": "window", "primitives": [b.primitive(window, 1)]}]
    lights = [directional("sun", (1.0, 0.92, 0.8), 3.0), point("room lamp", (1.0, 0.85, 0.7), 1.5, rng=8.0)]
    nodes = [
        {"name": "curtain", "mesh": 0, "rotation": upright},
        {"name": "window", "mesh": 1, "rotation": upright, "translation": [0.0, 0.0, -0.6]},
        light_node("sun", 0, [0.8, 3.0, -3.0], [0.0, 1.0, 0.5]),
        light_node("room lamp", 1, [-1.2, 2.0, 2.0]),
        camera_node("room", [0.3, 1.2, 2.7], [0.0, 1.2, 0.0], 0),
        camera_node("close", [0.08, 1.25, 0.22], [0.0, 1.2, 0.0], 1),
    ]
    return document("curtain", b, materials, meshes, nodes, lights,
                    [camera_def("room", 45.0, 0.1), camera_def("close", 30.0, 0.01)])


SCENES = {
    "closeup": closeup,
    "far": far,
    "grazing": grazing,
    "many_lights": many_lights,
    "twill_satin": twill_satin,
    "mirrored_uv": mirrored_uv,
    "spheres": spheres,
    "shadows": shadows,
    "skinned_cloth": skinned_cloth,
    "gltf_core": gltf_core,
    "curtain": curtain,
}


def main():
    """Writes every scene, or only those named on the command line (python3 tools/make_scenes.py
    shadows)."""
    names = sys.argv[1:] or list(SCENES)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        sys.exit("unknown scene(s) %s; known: %s" % (", ".join(unknown), ", ".join(SCENES)))
    os.makedirs(OUT, exist_ok=True)
    for name in names:
        build = SCENES[name]
        doc, binary = build()
        path = os.path.join(OUT, name + ".glb")
        write_glb(path, doc, binary)
        print("wrote %s (%d bytes)" % (os.path.relpath(path), os.path.getsize(path)))


if __name__ == "__main__":
    main()
