#!/usr/bin/env python3
"""Writes the catalogue of malformed and hostile scene files under tests/malformed/, and its table
tests/malformed/README.md (file, what is wrong, expected outcome), which tests/robustness.rs reads.

Each file is a small, well-formed scene (a lit quad) with one thing broken. Python 3 standard
library only; the output is byte-for-byte deterministic. Large inputs (ten million triangles, a
decoded texture of absurd size) are not written here: the catalogue holds header-only files that
claim the size, or tests/robustness.rs builds them at run time.

Run from anywhere:  python3 tools/make_malformed.py
"""

import base64
import json
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(os.path.dirname(HERE), "tests", "malformed")

NAN = float("nan")
INF = float("inf")

# --- building glTF documents ----------------------------------------------------------------------


class Doc:
    """A glTF document with one buffer: views and accessors are appended as an entry needs them."""

    def __init__(self):
        self.json = {
            "asset": {"version": "2.0", "generator": "weft tools/make_malformed.py"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "accessors": [],
            "bufferViews": [],
        }
        self.bin = bytearray()

    def push(self, key, value):
        self.json.setdefault(key, []).append(value)
        return len(self.json[key]) - 1

    def view(self, data):
        while len(self.bin) % 4:
            self.bin.append(0)
        offset = len(self.bin)
        self.bin.extend(data)
        return self.push("bufferViews", {"buffer": 0, "byteOffset": offset, "byteLength": len(data)})

    def floats(self, rows, kind):
        n = len(rows[0])
        data = b"".join(struct.pack("<%df" % n, *row) for row in rows)
        acc = {"bufferView": self.view(data), "componentType": 5126, "count": len(rows), "type": kind}
        if kind == "VEC3":
            # POSITION needs bounds; JSON has no NaN, so they are taken over the finite values.
            finite = [[v for v in (row[k] for row in rows) if v == v and abs(v) != INF] for k in range(3)]
            acc["min"] = [min(f) if f else 0.0 for f in finite]
            acc["max"] = [max(f) if f else 0.0 for f in finite]
        return self.push("accessors", acc)

    def indices(self, idx):
        data = struct.pack("<%dI" % len(idx), *idx)
        return self.push(
            "accessors", {"bufferView": self.view(data), "componentType": 5125, "count": len(idx), "type": "SCALAR"}
        )

    def mesh(self, positions, normals=None, uvs=None, tangents=None, indices=None, material=None):
        """A one-primitive mesh drawn by a new root node; returns the primitive's JSON object."""
        attributes = {"POSITION": self.floats(positions, "VEC3")}
        if normals is not None:
            attributes["NORMAL"] = self.floats(normals, "VEC3")
        if uvs is not None:
            attributes["TEXCOORD_0"] = self.floats(uvs, "VEC2")
        if tangents is not None:
            attributes["TANGENT"] = self.floats(tangents, "VEC4")
        prim = {"attributes": attributes}
        if indices is not None:
            prim["indices"] = self.indices(indices)
        if material is not None:
            prim["material"] = material
        mesh = self.push("meshes", {"name": "quad", "primitives": [prim]})
        node = self.push("nodes", {"name": "quad", "mesh": mesh})
        self.json["scenes"][0]["nodes"].append(node)
        return prim

    def light(self):
        """A directional key light from the front, above."""
        self.json.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
        self.json["extensions"] = {
            "KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3.0, "color": [1.0, 1.0, 1.0]}]}
        }
        # -Z of the node, rotated 30 degrees down about X: a quaternion [x, y, z, w].
        node = self.push(
            "nodes",
            {"name": "key", "rotation": [-0.258819, 0.0, 0.0, 0.965926], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        )
        self.json["scenes"][0]["nodes"].append(node)


QUAD_P = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]
QUAD_N = [[0.0, 0.0, 1.0]] * 4
QUAD_UV = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
QUAD_T = [[1.0, 0.0, 0.0, 1.0]] * 4
QUAD_I = [0, 1, 2, 0, 2, 3]


def quad_doc(positions=QUAD_P, normals=QUAD_N, uvs=QUAD_UV, tangents=None, indices=QUAD_I, material=True):
    """The base scene: a lit, textured-coordinate quad with a plain material."""
    d = Doc()
    if material:
        d.json["materials"] = [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6}}]
    d.mesh(positions, normals, uvs, tangents, indices, 0 if material else None)
    d.light()
    return d


def b64(data):
    return base64.b64encode(bytes(data)).decode("ascii")


def gltf(d, buffers=None):
    """The document as .gltf text, its buffer embedded as a data: URI (or `buffers`, if given)."""
    j = json.loads(json.dumps(d.json))
    if buffers is None:
        buffers = [{"byteLength": len(d.bin), "uri": "data:application/octet-stream;base64," + b64(d.bin)}]
    if buffers:
        j["buffers"] = buffers
    return (json.dumps(j, indent=1, sort_keys=True) + "\n").encode("utf-8")


def glb(d, with_bin=True):
    """The document as a .glb: JSON chunk, then the buffer as the binary chunk."""
    j = json.loads(json.dumps(d.json))
    binary = bytes(d.bin) + b"\0" * (-len(d.bin) % 4)
    j["buffers"] = [{"byteLength": len(d.bin)}]
    text = json.dumps(j, separators=(",", ":"), sort_keys=True).encode("utf-8")
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if with_bin:
        chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(width, height, rows=None):
    """An RGBA8 PNG. `rows` None: a header that claims width x height followed by one short IDAT
    (a few bytes of pixels, far fewer than the size claims) and IEND."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    if rows is None:
        raw = b"\0" + b"\x80" * 64
    else:
        raw = b"".join(b"\0" + bytes(r) for r in rows)
    return b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", zlib.compress(raw, 9)) + png_chunk(b"IEND", b"")


def textured_doc(image):
    """The quad with a base colour texture from `image` (a JSON image object)."""
    d = quad_doc()
    d.json["images"] = [image]
    d.json["textures"] = [{"source": 0}]
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    return d


def png_uri(data):
    return "data:image/png;base64," + b64(data)


def ktx2(width, height, level, vk_format=43, scheme=0, uncompressed=None):
    """A one-level 2D KTX2 file (R8G8B8A8_SRGB by default) whose level 0 is `level`, stored as
    given; `uncompressed` is the length the level index declares (that of `level` if None)."""
    samples = b"".join(struct.pack("<IIII", (c * 8) | 7 << 16 | ch << 24, 0, 0, 255) for c, ch in enumerate([0, 1, 2, 15]))
    block = struct.pack("<IHH4B4B8B", 0, 2, 24 + len(samples), 1, 1, 2, 0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 0, 0) + samples
    dfd = struct.pack("<I", 4 + len(block)) + block
    dfd_at = 80 + 24
    level_at = dfd_at + len(dfd)
    level_at += -level_at % 16
    header = b"\xabKTX 20\xbb\r\n\x1a\n" + struct.pack("<9I", vk_format, 1, width, height, 0, 0, 1, 1, scheme)
    header += struct.pack("<IIIIQQ", dfd_at, len(dfd), 0, 0, 0, 0)
    index = struct.pack("<QQQ", level_at, len(level), len(level) if uncompressed is None else uncompressed)
    out = header + index + dfd
    return out + b"\0" * (level_at - len(out)) + level


def ktx2_uri(data):
    return "data:image/ktx2;base64," + b64(data)


# --- the catalogue --------------------------------------------------------------------------------
#
# Each entry: file name, its bytes, what is wrong, the expected outcome, extra CLI arguments.
# Outcomes, as tests/robustness.rs reads them from the table:
#   error: `fragment`              loading (or the CLI) fails; the message holds the fragment and
#                                  the file name; the CLI exits with 1
#   renders                        loads without warnings and renders finite HDR and LDR images
#   renders, warning: `fragment`   renders, and one of the loader's warnings holds the fragment

ENTRIES = []


def entry(name, data, what, expected, args=""):
    assert "|" not in what + expected + args, name
    ENTRIES.append((name, data, what, expected, args))


def fabric_doc(fabric):
    d = quad_doc()
    d.json["materials"][0]["extensions"] = {"WEFT_materials_fabric": fabric}
    d.json["extensionsUsed"].append("WEFT_materials_fabric")
    return d


def camera_doc(perspective):
    d = quad_doc()
    d.json["cameras"] = [{"type": "perspective", "perspective": perspective}]
    node = d.push("nodes", {"name": "eye", "camera": 0, "translation": [0.0, 0.0, 4.0]})
    d.json["scenes"][0]["nodes"].append(node)
    return d


def add_animation(d, node, path, interpolation, times, values, kind):
    """An animation with one channel on `path` of `node`, keyframes `times` and `values`."""
    inp = d.push("accessors", {"bufferView": d.view(struct.pack("<%df" % len(times), *times)), "componentType": 5126,
                               "count": len(times), "type": "SCALAR", "min": [min(times)], "max": [max(times)]})
    flat = [x for row in values for x in row]
    count = len(flat) // {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[kind]
    out = d.push("accessors", {"bufferView": d.view(struct.pack("<%df" % len(flat), *flat)), "componentType": 5126, "count": count, "type": kind})
    d.json["animations"] = [{"name": "broken", "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
                             "samplers": [{"input": inp, "output": out, "interpolation": interpolation}]}]


def animated_doc(node, path, interpolation, values):
    """The quad with one animation channel of two keyframes (t = 0, 1) on `path` of `node`."""
    d = quad_doc()
    add_animation(d, node, path, interpolation, [0.0, 1.0], values, "VEC4" if path == "rotation" else "VEC3")
    return d


def morph_doc(delta, weights, targets):
    """The quad with `targets` morph targets moving its positions by `delta`, at mesh `weights`."""
    d = quad_doc()
    prim = d.json["meshes"][0]["primitives"][0]
    prim["targets"] = [{"POSITION": d.floats(delta, "VEC3")} for _ in range(targets)]
    d.json["meshes"][0]["weights"] = weights
    return d


def build():
    # Controls: what the broken files are broken from.
    entry("valid-quad.gltf", gltf(quad_doc()), "nothing: the control every other file is a variation of", "renders")
    entry("valid-quad.glb", glb(quad_doc()), "nothing: the control as a binary .glb", "renders")

    # --- the container ---------------------------------------------------------------------------
    good = glb(quad_doc())
    entry("truncated-in-json.glb", good[:40], ".glb cut off inside its JSON chunk", "error: `container is broken`")
    entry("truncated-in-bin.glb", good[: len(good) - 37], ".glb cut off inside its binary chunk (the header still claims the full length)", "error: `container is broken`")
    entry("glb-header-only.glb", good[:12], ".glb with a header and nothing else", "error: `container is broken`")
    entry("glb-length-below-header.glb", struct.pack("<4sII", b"glTF", 2, 4) + good[12:], ".glb header whose total length (4) is smaller than the header itself", "error: `container is broken`")
    entry("glb-version-1.glb", struct.pack("<4sII", b"glTF", 1, len(good)) + good[12:], ".glb container version 1", "error: `container is broken`")
    bad_chunk = bytearray(good)
    bad_chunk[16:20] = b"JSOX"
    entry("glb-unknown-chunk.glb", bytes(bad_chunk), ".glb whose first chunk is not JSON", "error: `container is broken`")
    entry("glb-missing-bin-chunk.glb", glb(quad_doc(), with_bin=False), ".glb whose buffer has no uri but the file has no binary chunk", "error: `has no uri`")
    entry("empty.gltf", b"", "an empty file", "error: `neither JSON nor a .glb`")
    entry("not-json.gltf", b"solid cube\nfacet normal 0 0 1\n", "an STL file named .gltf", "error: `neither JSON nor a .glb`")
    entry("broken-json.gltf", gltf(quad_doc())[:-40], ".gltf JSON cut off in the middle", "error: `does not parse`")
    entry("no-asset.gltf", b"{}\n", "JSON without the required \"asset\" object", "error: `\"asset\"`")
    entry("gltf-1.0.gltf", b'{"asset": {"version": "1.0"}, "meshes": {}}\n', "a glTF 1.0 file", "error: `glTF 1.0 file`")
    nested = b'{"asset": {"version": "2.0"}, "extras": ' + b"[" * 20000 + b"]" * 20000 + b"}\n"
    entry("deep-nesting.gltf", nested, "JSON nested 20000 arrays deep in \"extras\" (a stack-overflow attempt)", "error: `recursion limit`")

    # --- buffers -----------------------------------------------------------------------------------
    d = quad_doc()
    entry("missing-buffer.gltf", gltf(d, [{"byteLength": len(d.bin), "uri": "missing-buffer.bin"}]), "the buffer's file does not exist", "error: `missing-buffer.bin' does not exist`")
    entry("buffer-shorter-than-declared.gltf", gltf(d, [{"byteLength": len(d.bin) + 1000, "uri": "data:application/octet-stream;base64," + b64(d.bin)}]), "the buffer holds 1000 bytes fewer than its byteLength", "error: `holds only`")
    entry("buffer-without-uri.gltf", gltf(d, [{"byteLength": len(d.bin)}]), "a .gltf buffer with no uri (only a .glb may do that)", "error: `has no uri`")
    entry("buffer-bad-base64.gltf", gltf(d, [{"byteLength": len(d.bin), "uri": "data:application/octet-stream;base64,@@@@"}]), "the buffer's data: URI is not base64", "error: `base64 payload is malformed`")
    entry("buffer-remote-uri.gltf", gltf(d, [{"byteLength": len(d.bin), "uri": "https://example.com/quad.bin"}]), "the buffer is on the web", "error: `cannot fetch`")
    entry("buffer-uri-is-directory.gltf", gltf(d, [{"byteLength": len(d.bin), "uri": "."}]), "the buffer's uri names a directory", "error: `could not be read`")
    entry("no-buffers.gltf", gltf(d, []), "buffer views refer to buffer 0, but there are no buffers", "error: `refers to an object that does not exist`")
    d = quad_doc()
    d.json["bufferViews"][0]["byteOffset"] = 1 << 20
    entry("bufferview-past-buffer.gltf", gltf(d), "a buffer view starts 1 MiB into a buffer of a few hundred bytes", "error: `that buffer holds only`")
    d = quad_doc()
    d.json["accessors"][0]["count"] = 1000
    entry("accessor-past-view.gltf", gltf(d), "the POSITION accessor claims 1000 vertices; its buffer view holds 4", "error: `but the view is only`")
    d = quad_doc()
    d.json["accessors"][0]["count"] = 4294967295
    entry("accessor-huge-count.gltf", gltf(d), "the POSITION accessor claims 2^32 - 1 vertices", "error: `more than weft's limit of 33554432`")
    d = quad_doc()
    d.json["accessors"][3]["count"] = 300000000
    entry("indices-huge-count.gltf", gltf(d), "the index accessor claims 3 x 10^8 indices", "error: `more than weft's limit of 268435456`")
    # One mesh of a million (degenerate) triangles from an index accessor without a buffer view,
    # drawn by 300 nodes: 3 x 10^8 triangles a frame from 8 kB of JSON.
    d = Doc()
    pos = d.floats([[0.0, 0.0, 0.0]], "VEC3")
    zero = d.view(struct.pack("<I", 0))
    idx = d.push("accessors", {"componentType": 5125, "count": 3000000, "type": "SCALAR", "sparse": {"count": 1, "indices": {"bufferView": zero, "componentType": 5125}, "values": {"bufferView": zero}}})
    mesh = d.push("meshes", {"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]})
    for k in range(300):
        d.json["scenes"][0]["nodes"].append(d.push("nodes", {"mesh": mesh, "translation": [k * 0.01, 0.0, 0.0]}))
    entry("instanced-too-often.gltf", gltf(d), "300 nodes draw one mesh of a million triangles (from an index accessor without a buffer view)", "error: `brings the triangles drawn to`")
    d = quad_doc()
    d.json["accessors"][0]["byteOffset"] = 4294967295
    entry("accessor-huge-offset.gltf", gltf(d), "the POSITION accessor starts 4 GiB into its buffer view", "error: `reads accessor 0`")
    d = quad_doc()
    d.json["bufferViews"][0]["byteStride"] = 4
    entry("stride-too-small.gltf", gltf(d), "a buffer view of 12-byte positions with a byte stride of 4", "error: `byte stride`")
    d = quad_doc()
    del d.json["accessors"][0]["bufferView"]
    d.json["accessors"][0]["count"] = 30000000
    sparse_idx = d.view(struct.pack("<I", 1))
    sparse_val = d.view(struct.pack("<3f", 1.0, 0.0, 0.0))
    d.json["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": sparse_idx, "componentType": 5125}, "values": {"bufferView": sparse_val}}
    entry("accessor-no-view-huge-count.gltf", gltf(d), "a sparse POSITION accessor without a buffer view (zeros, one substitution) claiming 3 x 10^7 vertices: a 2 kB file asking for gigabytes", "error: `without a buffer view`")
    d = quad_doc()
    sparse_idx = d.view(struct.pack("<I", 9))
    sparse_val = d.view(struct.pack("<3f", 0.0, 0.0, 1.0))
    d.json["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": sparse_idx, "componentType": 5125}, "values": {"bufferView": sparse_val}}
    entry("sparse-index-out-of-range.gltf", gltf(d), "a sparse accessor substitutes element 9 of 4", "error: `sparse substitution for element 9`")

    # --- accessors and indices -----------------------------------------------------------------
    d = quad_doc()
    d.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 99
    entry("attribute-accessor-out-of-range.gltf", gltf(d), "NORMAL refers to accessor 99; there are 4", "error: `accessor 99`")
    d = quad_doc()
    d.json["meshes"][0]["primitives"][0]["indices"] = 99
    entry("indices-accessor-out-of-range.gltf", gltf(d), "the indices refer to accessor 99; there are 4", "error: `refers to an object that does not exist`")
    entry("index-out-of-range.gltf", gltf(quad_doc(indices=[0, 1, 2, 0, 2, 7])), "a triangle uses vertex 7 of 4", "error: `holds index 7`")
    entry("index-max-u32.gltf", gltf(quad_doc(indices=[0, 1, 4294967295])), "a triangle uses vertex 2^32 - 1", "error: `holds index 4294967295`")
    d = quad_doc()
    d.json["accessors"][3]["componentType"] = 5126
    entry("indices-float.gltf", gltf(d), "indices stored as floats", "error: `indices must be unsigned`")
    d = quad_doc()
    d.json["accessors"][0]["type"] = "VEC2"
    entry("position-vec2.gltf", gltf(d), "POSITION declared VEC2", "error: `has type VEC2 where VEC3 is required`")
    d = quad_doc()
    d.json["accessors"][1]["count"] = 3
    entry("attribute-count-mismatch.gltf", gltf(d), "NORMAL has 3 elements, POSITION 4", "error: `must have the same count`")
    d = quad_doc()
    del d.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
    entry("no-position.gltf", gltf(d), "a primitive without POSITION", "error: `POSITION`")
    entry("index-count-not-multiple-of-3.gltf", gltf(quad_doc(indices=[0, 1, 2, 0, 2, 3, 0])), "7 indices: the last is not a triangle", "renders, warning: `not a multiple of 3`")
    d = quad_doc()
    d.json["meshes"][0]["primitives"][0]["mode"] = 0
    entry("points-only.gltf", gltf(d), "the only primitive is POINTS (drawn: 1-pixel points)", "renders")

    # --- numbers that are not numbers ----------------------------------------------------------
    entry("nan-position.gltf", gltf(quad_doc(positions=[[-1.0, -1.0, 0.0], [1.0, NAN, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])), "a vertex position is NaN", "error: `non-finite position`")
    entry("inf-position.glb", glb(quad_doc(positions=[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [INF, 1.0, 0.0], [-1.0, 1.0, 0.0]])), "a vertex position is +Inf (.glb)", "error: `non-finite position`")
    entry("huge-positions.gltf", gltf(quad_doc(positions=[[-3e38, -3e38, 0.0], [3e38, -3e38, 0.0], [3e38, 3e38, 0.0], [-3e38, 3e38, 0.0]])), "positions near the f32 limit (finite, but their differences overflow: made mikktspace panic, and automatic framing NaN)", "renders")
    entry("nan-normals.gltf", gltf(quad_doc(normals=[[NAN, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, INF, 1.0], [0.0, 0.0, 1.0]])), "two normals are NaN and Inf", "renders, warning: `2 normal(s)`")
    entry("huge-normals.gltf", gltf(quad_doc(normals=[[0.0, 0.0, 3e38]] * 2 + [[1e30, 0.0, 1e30], [0.0, -1e-30, 1e-30]])), "normals of length 3e38 and 1.4e30 (valid directions, which normalising by squaring turned into zero) and 1.4e-30 (too short: replaced)", "renders, warning: `1 normal(s)`")
    entry("huge-tangents.gltf", gltf(quad_doc(tangents=[[3e38, 0.0, 0.0, 1.0], [1e30, 1e30, 0.0, -1.0], [1e-30, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]])), "tangents of length 3e38, 1.4e30 and 1e-30", "renders")
    entry("zero-length-normals.gltf", gltf(quad_doc(normals=[[0.0, 0.0, 0.0]] * 4)), "every normal is (0, 0, 0)", "renders, warning: `4 normal(s)`")
    entry("nan-tangents.gltf", gltf(quad_doc(tangents=[[NAN, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 0.0, NAN]])), "tangents NaN, zero, parallel to the normal, and with a NaN sign", "renders, warning: `3 tangent(s)`")
    entry("nan-uvs.gltf", gltf(quad_doc(uvs=[[NAN, 0.0], [1.0, INF], [1.0, 0.0], [-INF, NAN]])), "texture coordinates NaN and Inf", "renders, warning: `non-finite texture coordinate`")
    entry("huge-uvs.gltf", gltf(quad_doc(uvs=[[0.0, 0.0], [3e38, 0.0], [3e38, -3e38], [0.0, 3e38]])), "texture coordinates near the f32 limit (MikkTSpace and the weave divide by their differences)", "renders")
    entry("degenerate-triangles.gltf", gltf(quad_doc(positions=[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]], indices=[0, 1, 2, 0, 0, 0, 1, 1, 3, 0, 1, 3])), "zero-area triangles (collinear, repeated vertices) beside one good one", "renders, warning: `tangent(s)`")
    entry("coincident-corners.gltf", gltf(quad_doc(positions=[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, -1.0, 0.0], [-1.0, 1.0, 0.0]])), "every triangle has two corners at one position (made mikktspace read out of bounds; found by tests/fuzz_mutate.rs)", "renders")
    entry("collapsed-mesh.gltf", gltf(quad_doc(positions=[[0.5, 0.5, 0.5]] * 4)), "every vertex at one point (made mikktspace panic)", "renders")
    entry("all-triangles-degenerate.gltf", gltf(quad_doc(positions=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [0.0, 0.0, 0.0]], normals=None, indices=[0, 1, 2, 0, 3, 0])), "every triangle has zero area, and there are no normals to fall back on", "renders, warning: `covers no pixel`")
    d = quad_doc()
    d.json["nodes"][0]["rotation"] = [0.0, 0.0, 0.0, 0.0]
    entry("zero-quaternion.gltf", gltf(d), "a node rotation of (0, 0, 0, 0)", "error: `not a unit quaternion`")
    d = quad_doc()
    d.json["nodes"][0]["scale"] = [1e30, 1e30, 1e30]
    d.json["nodes"][0]["children"] = [d.push("nodes", {"name": "child", "scale": [1e30, 1e30, 1e30], "mesh": 0})]
    entry("scale-overflow.gltf", gltf(d), "nested node scales of 1e30 overflow to infinity", "error: `world transform that is not finite`")
    d = quad_doc()
    d.json["nodes"][0]["scale"] = [0.0, 0.0, 0.0]
    entry("zero-scale.gltf", gltf(d), "the mesh's node scales it to nothing", "renders")
    d = quad_doc()
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = [1e39, 0.5, 0.5, 1.0]
    entry("material-overflowing-factor.gltf", gltf(d), "a base colour factor of 1e39 (infinite as f32)", "error: `non-finite baseColorFactor`")
    d = quad_doc()
    d.json["materials"][0]["emissiveFactor"] = [1.0, 1.0, 1.0]
    d.json["materials"][0]["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 1e38}}
    d.json["extensionsUsed"].append("KHR_materials_emissive_strength")
    entry("emissive-huge.gltf", gltf(d), "emissive strength 1e38 (beyond half float, the HDR target's format)", "renders")
    d = quad_doc()
    d.json["materials"][0]["emissiveFactor"] = [4.0, 1.0, 1.0]
    d.json["materials"][0]["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 1e38}}
    d.json["extensionsUsed"].append("KHR_materials_emissive_strength")
    entry("emissive-overflow.gltf", gltf(d), "emissive factor 4 times strength 1e38: each finite, the product not (found by tests/fuzz_mutate.rs)", "error: `emitted radiance`")
    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 1e30
    entry("light-huge-intensity.gltf", gltf(d), "a directional light of 1e30 lux (beyond half float, the HDR target's format)", "renders")
    d = quad_doc()
    d.json["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 7.0
    d.json["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = -2.0
    entry("material-out-of-range.gltf", gltf(d), "metallic 7 and roughness -2", "renders, warning: `outside [0, 1]; clamped`")

    # --- textures --------------------------------------------------------------------------------
    entry("missing-texture.gltf", gltf(textured_doc({"uri": "missing-texture.png"})), "the base colour texture's file does not exist", "error: `missing-texture.png' does not exist`")
    entry("texture-absurd-size.gltf", gltf(textured_doc({"uri": png_uri(png(100000, 100000))})), "a PNG whose header claims 100000x100000 pixels (40 GB decoded)", "error: `100000x100000 pixels`")
    entry("texture-zero-size.gltf", gltf(textured_doc({"uri": png_uri(png(0, 0))})), "a PNG whose header claims 0x0 pixels", "error: `could not be decoded`")
    entry("texture-at-limit-truncated.gltf", gltf(textured_doc({"uri": png_uri(png(16384, 16384))})), "a PNG claiming 16384x16384 (the largest allowed; 1 GiB decoded) with only a few bytes of pixels", "error: `could not be decoded`")
    entry("texture-not-an-image.gltf", gltf(textured_doc({"uri": "data:application/octet-stream;base64," + b64(b"definitely not pixels" * 4)})), "the texture's bytes are text", "error: `weft reads PNG, JPEG, WebP and KTX2`")
    corrupt = bytearray(png(4, 4, [[200, 100, 50, 255] * 4] * 4))
    corrupt[40:48] = b"\xff" * 8
    entry("texture-corrupt-png.gltf", gltf(textured_doc({"uri": png_uri(bytes(corrupt))})), "a 4x4 PNG with its compressed pixels overwritten", "error: `could not be decoded`")
    entry("texture-gif.gltf", gltf(textured_doc({"uri": "data:image/gif;base64," + b64(b"GIF89a\x01\x00\x01\x00\x00\x00\x00;")})), "a GIF texture (glTF allows PNG and JPEG)", "error: `weft reads PNG, JPEG, WebP and KTX2`")
    texels = bytes([255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128])
    entry("texture-ktx2-rgba8.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, texels))})), "nothing: a 2x2 R8G8B8A8_SRGB KTX2 texture stored as is (the control of the KTX2 entries)", "renders")
    entry("texture-ktx2-zlib.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, zlib.compress(texels, 9), scheme=3, uncompressed=16))})), "nothing: the same texture under ZLIB supercompression", "renders")
    entry("texture-ktx2-truncated.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, texels)[:90])})), "a KTX2 texture cut off inside its level index", "error: `damaged KTX2 file (unexpected end of buffer)`")
    entry("texture-ktx2-absurd-size.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(100000, 100000, texels))})), "a KTX2 header that claims 100000x100000 pixels with 16 bytes of texels", "error: `100000x100000 pixels`")
    entry("texture-ktx2-short-level.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(4, 4, texels))})), "a 4x4 RGBA8 KTX2 texture whose level holds 16 bytes (one row of 64)", "error: `holds 16 bytes where its 4x4 format needs 64`")
    entry("texture-ktx2-bad-zstd.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, b"\x5a" * 24, scheme=2, uncompressed=16))})), "a KTX2 texture whose Zstandard stream is not one", "error: `Zstandard-compressed level 0 does not decode`")
    entry("texture-ktx2-zstd-bomb.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, b"\x5a" * 24, scheme=2, uncompressed=1 << 40))})), "a 2x2 KTX2 texture whose level index declares 1 TiB once decompressed", "error: `declares 1099511627776 uncompressed bytes where its 2x2 format needs 16`")
    entry("texture-ktx2-basislz.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(2, 2, texels, vk_format=0, scheme=1))})), "a KTX2 texture marked BasisLZ (ETC1S's supercompression) whose descriptor is RGBA and which has no BasisLZ global data", "error: `supercompression is BasisLZ but whose data format descriptor is not ETC1S`")
    entry("texture-ktx2-bc7.gltf", gltf(textured_doc({"uri": ktx2_uri(ktx2(4, 4, texels, vk_format=146))})), "a KTX2 texture in BC7_SRGB_BLOCK, which weft does not read", "error: `vkFormat BC7_SRGB_BLOCK, which weft does not read`")
    d = quad_doc()
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 5}
    entry("texture-index-out-of-range.gltf", gltf(d), "the material uses texture 5; there are none", "error: `refers to an object that does not exist`")
    d = textured_doc({"bufferView": 0, "mimeType": "image/png"})
    d.json["bufferViews"][0]["byteLength"] = 48
    entry("texture-from-geometry-view.gltf", gltf(d), "the image is read from the positions' buffer view", "error: `could not be decoded as Png`")

    # --- extensions ------------------------------------------------------------------------------
    d = quad_doc()
    d.json["extensionsRequired"] = ["KHR_materials_volume_scatter"]
    d.json["extensionsUsed"].append("KHR_materials_volume_scatter")
    entry("unsupported-required-extension.gltf", gltf(d), "requires KHR_materials_volume_scatter", "error: `requires the glTF extension 'KHR_materials_volume_scatter'`")
    d = quad_doc()
    d.json["extensionsUsed"].append("MSFT_lod")
    entry("unsupported-used-extension.gltf", gltf(d), "uses (without requiring) an extension weft does not know", "renders, warning: `which weft ignores`")
    entry(
        "fabric-all-out-of-range.gltf",
        gltf(fabric_doc({
            "pattern": "twill", "repeat": -5.0, "gap": 99.0, "e_along": -1.0, "e_across": 1e30,
            "rd": [2.0, -1.0, 0.5], "rd_warp": 7.0, "rd_weft": [-3.0, 4.0, 1e30], "rs": 5.0,
            "shadow_strength": -2.0, "shadow_width": 40.0, "shiny": True,
        })),
        "WEFT_materials_fabric with every numeric field outside its range (and an unknown field)",
        "renders, warning: `clamped`",
    )
    entry("fabric-wrong-types.gltf", gltf(fabric_doc({"repeat": "wide", "rd": [0.5, 0.5]})), "WEFT_materials_fabric with a string repeat and a two-number rd", "error: `WEFT_materials_fabric.rd must be`")
    entry("fabric-unknown-pattern.gltf", gltf(fabric_doc({"pattern": "houndstooth"})), "WEFT_materials_fabric pattern \"houndstooth\"", "error: `houndstooth`")
    entry("fabric-not-an-object.gltf", gltf(fabric_doc([1, 2, 3])), "WEFT_materials_fabric is an array", "error: `must be a JSON object`")
    entry("fabric-huge-custom-pattern.gltf", gltf(fabric_doc({"pattern": ["10" * 500] * 9})), "WEFT_materials_fabric custom pattern of 9 rows of 1000 cells (at most 8 x 8 are allowed)", "error: `pattern`")

    # --- scenes, cameras, lights -----------------------------------------------------------------
    d = Doc()
    d.light()
    entry("no-meshes.gltf", gltf(d), "a scene with a light and 0 meshes", "renders, warning: `nothing to draw`")
    entry("no-scenes-no-nodes.gltf", b'{"asset": {"version": "2.0"}}\n', "only the asset object: no scenes, nodes or meshes", "renders, warning: `nothing to draw`")
    entry("camera-zero-fov.gltf", gltf(camera_doc({"yfov": 0.0, "znear": 0.1})), "a perspective camera with yfov 0", "error: `has yfov 0 rad`")
    entry("camera-negative-fov.gltf", gltf(camera_doc({"yfov": -0.7, "znear": 0.1})), "a perspective camera with yfov -0.7", "error: `has yfov -0.7 rad`")
    entry("camera-fov-pi.gltf", gltf(camera_doc({"yfov": 3.2, "znear": 0.1})), "a perspective camera with yfov 3.2 (more than 180 degrees)", "error: `has yfov 3.2 rad`")
    entry("camera-znear-zero.gltf", gltf(camera_doc({"yfov": 0.7, "znear": 0.0})), "a perspective camera with znear 0", "error: `has znear 0`")
    entry("camera-zfar-before-znear.gltf", gltf(camera_doc({"yfov": 0.7, "znear": 1.0, "zfar": 0.5})), "zfar 0.5 in front of znear 1", "error: `zfar must be greater than znear`")
    entry("valid-quad-fov-zero.gltf", gltf(quad_doc()), "a valid scene, rendered with --eye/--target and --fov 0", "error: `field of view 0 degrees`", "--eye 0,0,4 --target 0,0,0 --fov 0")
    entry("valid-quad-fov-negative.gltf", gltf(quad_doc()), "a valid scene, rendered with --eye/--target and --fov=-30", "error: `field of view -30`", "--eye 0,0,4 --target 0,0,0 --fov=-30")
    entry("valid-quad-size-100000.gltf", gltf(quad_doc()), "a valid scene, rendered with --size 100000x100000", "error: `between 1 and 16384`", "--size 100000x100000")
    entry("valid-quad-size-zero.gltf", gltf(quad_doc()), "a valid scene, rendered with --size 0x720", "error: `between 1 and 16384`", "--size 0x720")
    entry("valid-quad-camera-7.gltf", gltf(quad_doc()), "a valid scene without cameras, rendered with --camera 7", "error: `camera 7 does not exist`", "--camera 7")
    d = quad_doc()
    d.json["nodes"][0]["children"] = [0]
    entry("node-cycle.gltf", gltf(d), "a node that is its own child", "error: `reached twice`")
    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = -3.0
    entry("light-negative-intensity.gltf", gltf(d), "a light with intensity -3", "error: `has intensity -3`")
    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"] = [{"type": "spot", "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}}]
    entry("light-bad-spot-cone.gltf", gltf(d), "a spot light whose inner cone is wider than its outer cone", "error: `innerConeAngle 1 and outerConeAngle 0.5`")
    d = quad_doc()
    d.json["nodes"][1]["extensions"]["KHR_lights_punctual"]["light"] = 3
    entry("light-index-out-of-range.gltf", gltf(d), "a node refers to light 3; there is one", "error: `light refers to an object that does not exist`")
    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"][0]["extras"] = {"shadows": "yes"}
    entry("light-shadows-string.gltf", gltf(d), "a light asks for shadows with \"extras\": {\"shadows\": \"yes\"} (true, false or an object is allowed)", "error: `extras.shadows = \"yes\"`")
    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"][0]["extras"] = {"shadows": {"resolution": -5, "filter_radius": 99, "bias": -3}}
    entry("light-shadows-out-of-range.gltf", gltf(d), "a light's shadow map settings resolution -5, filter_radius 99 and bias -3", "renders, warning: `resolution = -5, which is outside [64, 4096]; clamped to 64`")
    d = quad_doc()
    d.json["nodes"][0]["extras"] = {"cast_shadows": 3}
    entry("node-cast-shadows-number.gltf", gltf(d), "a node's \"extras\": {\"cast_shadows\": 3} (true or false is allowed)", "error: `extras.cast_shadows = 3`")

    # Degenerate output sizes: readbacks smaller than the 16 bytes a Vulkan buffer is made at least.
    for size in ["1x1", "1x2", "3x1"]:
        entry("valid-quad-size-%s.gltf" % size, gltf(quad_doc()), "a valid scene, rendered at --size %s (an image of %d bytes)" % (size, 4 * eval(size.replace("x", "*"))), "renders", "--size " + size)

    # Animation channels: every bad one is dropped with a warning naming it, the scene still loads.
    entry("animation-target-missing-node.gltf", gltf(animated_doc(99, "translation", "LINEAR", [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])),
          "an animation channel whose target node 99 does not exist (the gltf crate's validator misses it, and its walk panicked)", "renders, warning: `targets node 99`")
    entry("animation-zero-rotation-linear.gltf", gltf(animated_doc(0, "rotation", "LINEAR", [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])),
          "a LINEAR rotation channel with a zero-length quaternion keyframe (interpolated, it made the node's transform NaN)", "renders, warning: `which has zero length`")
    entry("animation-zero-rotation-step.gltf", gltf(animated_doc(0, "rotation", "STEP", [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])),
          "a STEP rotation channel with a zero-length quaternion keyframe (it collapsed the node)", "renders, warning: `which has zero length`")
    d = morph_doc([[0.0, 0.0, 0.1]] * 4, weights=[0.0, 0.0], targets=2)
    add_animation(d, 0, "weights", "LINEAR", [0.0, 1.0], [[0.0], [0.5], [1.0]], "SCALAR")
    entry("animation-weights-count-mismatch.gltf", gltf(d),
          "a weights channel of a mesh with 2 morph targets: 2 keyframes, 3 output scalars (4 needed)", "renders, warning: `2 keyframe times but 3 output values`")

    # KHR_animation_pointer and KHR_node_visibility (ratified): files using them were refused
    # whole ("missing field `node`"); a pointer weft cannot follow is a warning, the rest plays.
    def pointer_doc(pointer, kind, values):
        d = quad_doc()
        add_animation(d, 0, "translation", "LINEAR", [0.0, 1.0], values, kind)
        d.json["animations"][0]["channels"][0]["target"] = {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}
        d.json["extensionsUsed"] = d.json.get("extensionsUsed", []) + ["KHR_animation_pointer"]
        d.json["extensionsRequired"] = ["KHR_animation_pointer"]
        return d
    entry("animation-pointer-valid.gltf", gltf(pointer_doc("/materials/0/pbrMetallicRoughness/baseColorFactor", "VEC4", [[1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]])),
          "nothing: a KHR_animation_pointer channel on a material's base colour (such a file was refused as invalid)", "renders")
    entry("animation-pointer-unknown-property.gltf", gltf(pointer_doc("/materials/0/pbrMetallicRoughness/baseColorTexture/texCoord", "SCALAR", [[0.0], [1.0]])),
          "a KHR_animation_pointer channel on a property weft does not animate (a texture's texCoord)", "renders, warning: `which weft does not animate`")
    entry("animation-pointer-missing-material.gltf", gltf(pointer_doc("/materials/9/emissiveFactor", "VEC3", [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])),
          "a KHR_animation_pointer channel on material 9 of a file with one", "renders, warning: `points at material 9`")
    entry("animation-pointer-not-a-pointer.gltf", gltf(pointer_doc("materials/0/alphaCutoff", "SCALAR", [[0.0], [1.0]])),
          "a KHR_animation_pointer \"pointer\" that does not start with '/'", "renders, warning: `not a JSON pointer`")
    d = quad_doc()
    d.json["nodes"][0]["extensions"] = {"KHR_node_visibility": {"visible": "no"}}
    d.json["extensionsUsed"] = d.json.get("extensionsUsed", []) + ["KHR_node_visibility"]
    entry("node-visibility-not-boolean.gltf", gltf(d), "KHR_node_visibility with \"visible\": \"no\" (a string, not a boolean)", "renders, warning: `not true or false`")

    # Finite numbers whose products overflow: refused or repaired where the product is made.
    d = quad_doc()
    joints = d.push("accessors", {"bufferView": d.view(struct.pack("<16B", *([0] * 16))), "componentType": 5121, "count": 4, "type": "VEC4"})
    weights = d.floats([[1.0, 0.0, 0.0, 0.0]] * 4, "VEC4")
    prim = d.json["meshes"][0]["primitives"][0]
    prim["attributes"]["JOINTS_0"] = joints
    prim["attributes"]["WEIGHTS_0"] = weights
    ibm = d.push("accessors", {"bufferView": d.view(struct.pack("<16f", 1e30, 0, 0, 0, 0, 1e30, 0, 0, 0, 0, 1e30, 0, 0, 0, 0, 1)), "componentType": 5126, "count": 1, "type": "MAT4"})
    joint = d.push("nodes", {"name": "joint", "scale": [1e30, 1e30, 1e30]})
    d.json["scenes"][0]["nodes"].append(joint)
    d.json["skins"] = [{"name": "huge", "joints": [joint], "inverseBindMatrices": ibm}]
    d.json["nodes"][0]["skin"] = 0
    entry("skin-joint-matrix-overflow.gltf", gltf(d), "a skin whose inverse bind matrix scales by 1e30 and whose joint scales by 1e30: each finite, their product not (the mesh vanished)", "error: `overflows 32-bit floating point`")
    entry("morph-weight-overflow.gltf", gltf(morph_doc([[3e38, 0.0, 0.0]] * 4, weights=[3e38], targets=1)),
          "a morph target weight of 3e38 on a delta of 3e38 (the mesh vanished)", "error: `out of the range of 32-bit floating point`")
    d = morph_doc([[3e38, 0.0, 0.0]] * 4, weights=[0.0], targets=1)
    add_animation(d, 0, "weights", "LINEAR", [0.0, 1.0], [[0.0], [3e38]], "SCALAR")
    entry("animation-morph-weight-overflow.gltf", gltf(d),
          "a morph target delta of 3e38, animated from weight 0 to 3e38: the rest pose is fine; posed at t = 0.5 the product overflows (tests/animation.rs poses it: an error naming the mesh)", "renders")
    tiny = png(2, 2, [[255, 0, 0, 255, 0, 255, 0, 255], [0, 0, 255, 255, 255, 255, 255, 128]])
    d = textured_doc({"uri": png_uri(tiny)})
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {"KHR_texture_transform": {"scale": [3e38, 3e38], "offset": [3e38, 3e38]}}
    d.json["extensionsUsed"].append("KHR_texture_transform")
    entry("texture-transform-overflow.gltf", gltf(d), "a KHR_texture_transform of scale and offset 3e38: finite, but at texture coordinate 1 the result is not (the surface was black)", "renders, warning: `out of the range of 32-bit floating point`")
    d = textured_doc({"uri": png_uri(tiny)})
    d.json["meshes"] = []
    d.json["nodes"] = d.json["nodes"][1:]
    d.json["scenes"][0]["nodes"] = [0]
    d.mesh(QUAD_P, QUAD_N, [[0.0, 1e20], [1e20, 1e20], [1e20, 0.0], [0.0, 0.0]], None, QUAD_I, 0)
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {"KHR_texture_transform": {"scale": [1e19, 1e19]}}
    d.json["extensionsUsed"].append("KHR_texture_transform")
    entry("texture-transform-overflow-baked.gltf", gltf(d), "texture coordinates of 1e20 through a KHR_texture_transform scale of 1e19 (baked into the vertices: 1e39 overflows)", "renders, warning: `made so by its material's KHR_texture_transform`")

    # KHR_materials_variants: a mapping is checked against the file's materials, not the loader's.
    d = Doc()
    d.json["materials"] = [{"name": "grey"}]
    d.mesh(QUAD_P, QUAD_N, QUAD_UV, None, QUAD_I, None)
    prim = d.mesh([[p[0] + 3.0, p[1], p[2]] for p in QUAD_P], QUAD_N, QUAD_UV, None, QUAD_I, 0)
    prim["extensions"] = {"KHR_materials_variants": {"mappings": [{"material": 1, "variants": [0]}]}}
    d.json["extensions"] = {"KHR_materials_variants": {"variants": [{"name": "red"}]}}
    d.json["extensionsUsed"] = ["KHR_materials_variants"]
    d.light()
    d.json["extensions"]["KHR_materials_variants"] = {"variants": [{"name": "red"}]}
    entry("variant-mapping-past-materials.gltf", gltf(d), "a variant maps a primitive to material 1 of a file with one material (weft's own default material, made for another primitive, sat at index 1)", "error: `names material 1, but the file has 1 materials`", "--variant red")

    # Made at run time by tests/robustness.rs (120 MB of indices): listed so the table is complete.
    ENTRIES.append((
        "ten-million-triangles.glb", None,
        "10 million triangles: one index buffer of 30 million indices over a 2049 x 2049 vertex grid, made by the test at run time (not committed)",
        "renders", "--size 320x180",
    ))


# --- fuzz seeds -----------------------------------------------------------------------------------
#
# Valid scenes that between them use every part of glTF the loader reads, for the coverage-guided
# fuzzer (tools/fuzz/corpus/scene_loader/seed-*; the fuzzer's own finds sit beside them).

CORPUS = os.path.join(HERE, "fuzz", "corpus", "scene_loader")


def seeds():
    out = []
    with open(os.path.join(os.path.dirname(HERE), "assets", "default.gltf"), "rb") as f:
        out.append(("seed-default-scene.gltf", f.read()))
    out.append(("seed-quad.gltf", gltf(quad_doc())))
    out.append(("seed-quad.glb", glb(quad_doc())))

    tiny = png(2, 2, [[255, 0, 0, 255, 0, 255, 0, 255], [0, 0, 255, 255, 255, 255, 255, 128]])
    d = quad_doc(tangents=QUAD_T)
    d.json["images"] = [{"uri": png_uri(tiny)}, {"bufferView": d.view(tiny), "mimeType": "image/png", "name": "in-buffer"}]
    d.json["samplers"] = [{"magFilter": 9728, "wrapS": 33071}]
    d.json["textures"] = [{"source": 0, "sampler": 0}, {"source": 1}]
    transform = {"KHR_texture_transform": {"offset": [0.5, 0.0], "rotation": 0.3, "scale": [2.0, 2.0], "texCoord": 0}}
    d.json["materials"][0] = {
        "name": "textured",
        "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "extensions": transform},
            "metallicRoughnessTexture": {"index": 1, "texCoord": 1},
        },
        "normalTexture": {"index": 1, "scale": 0.5, "extensions": transform},
        "occlusionTexture": {"index": 0},
        "emissiveTexture": {"index": 0},
        "emissiveFactor": [1.0, 0.5, 0.0],
        "alphaMode": "BLEND",
        "doubleSided": True,
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
    }
    d.json["extensionsUsed"] += ["KHR_texture_transform", "KHR_materials_emissive_strength"]
    out.append(("seed-textured.gltf", gltf(d)))

    d = fabric_doc({
        "pattern": ["|-|", "-|-"], "repeat": 0.1, "gap": 0.01, "e_along": 150.0, "e_across": 8.0,
        "rd_warp": [0.6, 0.1, 0.1], "rd_weft": 0.3, "rs": 0.05, "shadow_strength": 0.4,
        "shadow_width": 0.3, "coupled_diffuse": True, "extras": {"note": "seed"},
    })
    d.json["extensionsRequired"] = ["WEFT_materials_fabric"]
    out.append(("seed-fabric.gltf", gltf(d)))
    out.append(("seed-fabric-satin.glb", glb(fabric_doc({"pattern": "satin", "rd": [0.2, 0.3, 0.4]}))))

    d = quad_doc()
    d.json["extensions"]["KHR_lights_punctual"]["lights"] += [
        {"type": "point", "intensity": 40.0, "range": 10.0, "color": [1.0, 0.8, 0.6], "name": "bulb"},
        {"type": "spot", "intensity": 90.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
    ]
    d.json["cameras"] = [
        {"type": "perspective", "name": "main", "perspective": {"yfov": 0.8, "znear": 0.05, "zfar": 100.0, "aspectRatio": 1.5}},
        {"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}},
    ]
    bulb = d.push("nodes", {"translation": [1.0, 2.0, 1.0], "extensions": {"KHR_lights_punctual": {"light": 1}}})
    spot = d.push("nodes", {"matrix": [1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 3, 0, 1], "extensions": {"KHR_lights_punctual": {"light": 2}}})
    cam = d.push("nodes", {"camera": 0, "translation": [0.0, 0.5, 4.0], "scale": [2.0, 2.0, 2.0], "children": [bulb, spot]})
    ortho = d.push("nodes", {"camera": 1, "rotation": [0.0, 0.7071068, 0.0, 0.7071068]})
    d.json["scenes"][0]["nodes"] += [cam, ortho]
    d.json["scenes"].append({"name": "second", "nodes": [0]})
    out.append(("seed-lights-cameras.gltf", gltf(d)))

    # Interleaved attributes in one strided view, normalised integer UVs, byte indices, a sparse
    # accessor, a second (line) primitive, morph targets, vertex colours, a skin, a reused mesh.
    d = quad_doc()
    inter = b"".join(struct.pack("<3f3f", *(p + n)) for p, n in zip(QUAD_P, QUAD_N))
    v = d.view(inter)
    d.json["bufferViews"][v]["byteStride"] = 24
    pos = d.push("accessors", {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]})
    nrm = d.push("accessors", {"bufferView": v, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"})
    uv = d.push("accessors", {"bufferView": d.view(bytes([0, 255, 255, 255, 255, 0, 0, 0])), "componentType": 5121, "normalized": True, "count": 4, "type": "VEC2"})
    idx = d.push("accessors", {"bufferView": d.view(bytes([0, 1, 2, 0, 2, 3])), "componentType": 5121, "count": 6, "type": "SCALAR"})
    col = d.push("accessors", {"bufferView": d.view(struct.pack("<16H", *([65535] * 16))), "componentType": 5123, "normalized": True, "count": 4, "type": "VEC4"})
    sp_i = d.view(struct.pack("<H", 2))
    sp_v = d.view(struct.pack("<3f", 0.0, 0.0, 0.5))
    d.json["accessors"][pos]["sparse"] = {"count": 1, "indices": {"bufferView": sp_i, "componentType": 5123}, "values": {"bufferView": sp_v}}
    morph = d.push("accessors", {"componentType": 5126, "count": 4, "type": "VEC3", "sparse": {"count": 1, "indices": {"bufferView": sp_i, "componentType": 5123}, "values": {"bufferView": sp_v}}})
    lines = d.push("accessors", {"bufferView": d.view(struct.pack("<4H", 0, 1, 1, 2)), "componentType": 5123, "count": 4, "type": "SCALAR"})
    mesh = d.push("meshes", {"name": "packed", "weights": [0.5], "primitives": [
        {"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv, "COLOR_0": col}, "indices": idx, "material": 0, "targets": [{"POSITION": morph}]},
        {"attributes": {"POSITION": pos}, "indices": lines, "mode": 1},
    ]})
    joint = d.push("nodes", {"name": "joint"})
    d.json["skins"] = [{"joints": [joint]}]
    a = d.push("nodes", {"mesh": mesh, "skin": 0, "translation": [2.5, 0.0, 0.0]})
    b = d.push("nodes", {"mesh": mesh, "translation": [-2.5, 0.0, 0.0], "children": [joint]})
    d.json["scenes"][0]["nodes"] += [a, b]
    out.append(("seed-packed-attributes.glb", glb(d)))

    # No scene: every root node is drawn; no indices, no normals, no UVs.
    d = Doc()
    d.mesh([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.5], [2.0, 1.0, 0.0], [1.0, 2.0, 0.0]])
    del d.json["scene"]
    del d.json["scenes"]
    out.append(("seed-no-scene-no-indices.gltf", gltf(d)))

    # KHR_texture_basisu: a 2x2 RGBA8 KTX2 texture under ZLIB, in the binary chunk for the fuzzer
    # to mutate (header, level index, descriptor and stream).
    d = quad_doc()
    texels = bytes([255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128])
    ktx = ktx2(2, 2, zlib.compress(texels, 9), scheme=3, uncompressed=16)
    d.json["images"] = [{"bufferView": d.view(ktx), "mimeType": "image/ktx2"}]
    d.json["textures"] = [{"extensions": {"KHR_texture_basisu": {"source": 0}}}]
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    d.json["extensionsUsed"] = d.json.get("extensionsUsed", []) + ["KHR_texture_basisu"]
    d.json["extensionsRequired"] = ["KHR_texture_basisu"]
    out.append(("seed-ktx2.glb", glb(d)))
    return out


def main():
    os.makedirs(CORPUS, exist_ok=True)
    for name, data in seeds():
        with open(os.path.join(CORPUS, name), "wb") as f:
            f.write(data)
    build()
    os.makedirs(OUT, exist_ok=True)
    keep = {"README.md"}
    total = 0
    for name, data, _, _, _ in ENTRIES:
        if data is None:
            continue
        keep.add(name)
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
        total += len(data)
    for stale in sorted(set(os.listdir(OUT)) - keep):
        os.remove(os.path.join(OUT, stale))
    lines = [
        "# Malformed and hostile scene files",
        "",
        "Written by `tools/make_malformed.py` (do not edit by hand: edit the script and run it again);",
        "checked by `tests/robustness.rs`, which reads this table. Each file is the same small scene (a",
        "lit quad) with one thing broken. *Expected*: `error:` the load (or the command line) fails with",
        "a message holding the fragment and naming the file (where the file is at fault), and `weft`",
        "exits with 1, having written nothing; `renders`: the scene loads and renders on lavapipe with",
        "validation on, with finite HDR and LDR images, and, where a `warning:` is given, one of the",
        "loader's warnings holds it. *Arguments* are added to `weft render FILE` (and to the render",
        "options of the in-process test).",
        "",
        "| file | what is wrong | expected | arguments |",
        "|---|---|---|---|",
    ]
    for name, _, what, expected, args in ENTRIES:
        lines.append("| `%s` | %s | %s | %s |" % (name, what, expected, "`%s`" % args if args else ""))
    lines.append("")
    with open(os.path.join(OUT, "README.md"), "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines))
    print("wrote %d files (%d bytes) and README.md to %s, and %d fuzz seeds to %s" % (len(keep) - 1, total, OUT, len(seeds()), CORPUS))


if __name__ == "__main__":
    main()
