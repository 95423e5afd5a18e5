#!/usr/bin/env python3
"""Writes weft's ETC1S (KHR_texture_basisu, BasisLZ) test files with Binomial's own encoder and
KTX2 writer, so that weft's ETC1S reader is judged on files it did not write:

- builds the `basisu` command-line tool (Basis Universal v1.16.4) from the sources the
  `basis-universal-sys` crate vendors (in Cargo's registry after any `cargo build` of weft), with g++;
- tests/data/ktx2/pattern_etc1s.ktx2: pattern.png (RGBA, 62 x 46) as ETC1S with an alpha slice;
  pattern_etc1s_mips.ktx2: the same with its mip chain (seven levels, seven image descriptors);
  pattern_etc1s_opaque.ktx2: pattern.png's colour without alpha (no alpha slice);
- tests/data/ktx2/pattern_etc1s_reference.png, pattern_etc1s_mips_reference.png (level 0: the
  mip chain shares one codebook, so level 0 differs) and pattern_etc1s_opaque_reference.png: what
  Binomial's transcoder makes of the same encodings in its own .basis container (`basisu -unpack`,
  RGBA32): the exact texels an ETC1S reader must return (the encoder is deterministic; the RGB also
  equals the ETC1 blocks basisu's KTX2 transcoder writes for the .ktx2 files, checked here);
- tests/data/compressed/avocado_etc1s.glb: avocado_small.glb with each PNG texture replaced by an
  ETC1S KTX2 file (base colour with sRGB metrics, the others -linear, as gltf-transform's `etc1s`
  does), referenced as gltf-transform does (KHR_texture_basisu required, no core source).

Needs python3 with Pillow and NumPy, g++, and a built weft (for the registry sources).
Run from anywhere:  python3 tools/make_etc1s_test_files.py
"""

import glob
import io
import json
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
KTX2 = os.path.join(ROOT, "tests", "data", "ktx2")
COMPRESSED = os.path.join(ROOT, "tests", "data", "compressed")


def build_basisu(work):
    cargo_home = os.environ.get("CARGO_HOME", os.path.expanduser("~/.cargo"))
    found = sorted(glob.glob(os.path.join(cargo_home, "registry", "src", "*", "basis-universal-sys-0.3.1", "vendor", "basis_universal")))
    if not found:
        sys.exit("basis-universal-sys 0.3.1's sources are not in Cargo's registry: run `cargo build --release` in weft first")
    src = found[0]
    exe = os.path.join(work, "basisu")
    cmd = ["g++", "-O2", "-std=c++17", "-fno-strict-aliasing", "-w",
           "-DBASISD_SUPPORT_KTX2_ZSTD=1", "-DBASISU_SUPPORT_SSE=0", "-DBASISU_SUPPORT_OPENCL=0",
           "-I" + src, os.path.join(src, "basisu_tool.cpp")]
    cmd += sorted(glob.glob(os.path.join(src, "encoder", "*.cpp")))
    cmd += [os.path.join(src, "transcoder", "basisu_transcoder.cpp"), os.path.join(src, "zstd", "zstd.c"),
            "-o", exe, "-lpthread"]
    print("building basisu from", src)
    subprocess.run(cmd, check=True)
    return exe


def basisu(exe, *args, cwd):
    subprocess.run([exe, *args], check=True, cwd=cwd, stdout=subprocess.DEVNULL)


def reference(exe, png, work, extra):
    """Binomial's RGBA32 transcode of level 0 of `png` encoded as ETC1S in a .basis file with the
    options `extra`."""
    out = os.path.join(work, "unpack-" + os.path.basename(png) + "".join(extra))
    os.makedirs(out, exist_ok=True)
    basis = os.path.join(out, "x.basis")
    basisu(exe, png, "-output_file", basis, *extra, cwd=out)
    basisu(exe, "-unpack", "-no_ktx", basis, cwd=out)  # RGBA32 is among what -unpack writes
    rgb = np.array(Image.open(os.path.join(out, "x_unpacked_rgb_RGBA32_0_0000.png")).convert("RGB"))
    alpha = np.array(Image.open(os.path.join(out, "x_unpacked_a_RGBA32_0_0000.png")).convert("L"))
    return np.dstack([rgb, alpha])


def check_etc1_equals(exe, ktx2, rgba, work):
    """The RGB of `rgba` equals the ETC1 blocks basisu's KTX2 transcoder writes for `ktx2`."""
    out = os.path.join(work, "etc1-" + os.path.basename(ktx2))
    os.makedirs(out, exist_ok=True)
    basisu(exe, "-unpack", "-no_ktx", "-etc1_only", ktx2, cwd=out)
    stem = os.path.splitext(os.path.basename(ktx2))[0]
    # Level 0: "_0_0000" without a mip chain, "_0_0_0000" (level, layer) with one.
    level0 = sorted(glob.glob(os.path.join(out, stem + "_unpacked_rgb_ETC1_RGB_0_*0000.png")))[0]
    etc1 = np.array(Image.open(level0).convert("RGB"))
    diff = np.abs(etc1.astype(int) - rgba[..., :3].astype(int)).max()
    assert diff == 0, f"{ktx2}: the .basis reference and the KTX2 transcode differ by {diff}"


def glb_parts(path):
    data = open(path, "rb").read()
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    return doc, bytearray(data[20 + json_len + 8:])


def glb(doc, bin_):
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    bin_ = bytes(bin_) + b"\0" * (-len(bin_) % 4)
    total = 12 + 8 + len(text) + 8 + len(bin_)
    return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(text), 0x4E4F534A) + text
            + struct.pack("<II", len(bin_), 0x004E4942) + bin_)


def ktx2_glb(exe, src, dst, mode, work):
    """`src` (.glb) with each image re-encoded by basisu as KTX2 (`mode`: [] for ETC1S, ["-uastc"]
    for UASTC + Zstandard): base colour, emissive, sheen colour and specular colour images with
    sRGB metrics, the others -linear (as gltf-transform's `etc1s`/`uastc` do), referenced as
    gltf-transform does (KHR_texture_basisu required, no core source); the old image bytes stay in
    the binary chunk, unreferenced."""
    doc, bin_ = glb_parts(src)
    srgb_slots = ("baseColorTexture", "emissiveTexture", "sheenColorTexture", "specularColorTexture")

    def textures_in(node):
        if isinstance(node, dict):
            for k, v in node.items():
                if isinstance(v, dict) and "index" in v:
                    yield k, v["index"]
                yield from textures_in(v)
        elif isinstance(node, list):
            for v in node:
                yield from textures_in(v)

    srgb = {doc["textures"][i]["source"] for m in doc.get("materials", [])
            for k, i in textures_in(m) if k in srgb_slots}
    for i, img in enumerate(doc["images"]):
        view = doc["bufferViews"][img["bufferView"]]
        at = view.get("byteOffset", 0)
        png = os.path.join(work, f"image{i}.png")
        Image.open(io.BytesIO(bytes(bin_[at:at + view["byteLength"]]))).save(png)
        ktx2 = os.path.join(work, f"image{i}.ktx2")
        basisu(exe, "-ktx2", *mode, png, "-output_file", ktx2, *([] if i in srgb else ["-linear"]), cwd=work)
        data = open(ktx2, "rb").read()
        bin_ += b"\0" * (-len(bin_) % 16)
        doc["bufferViews"].append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data)})
        bin_ += data
        doc["images"][i] = {"bufferView": len(doc["bufferViews"]) - 1, "mimeType": "image/ktx2"}
    for t in doc["textures"]:
        t["extensions"] = {"KHR_texture_basisu": {"source": t.pop("source")}}
    for key in ["extensionsUsed", "extensionsRequired"]:
        doc[key] = sorted(set(doc.get(key, [])) | {"KHR_texture_basisu"})
    doc["buffers"][0]["byteLength"] = len(bin_) + (-len(bin_) % 4)
    open(dst, "wb").write(glb(doc, bin_))


def main():
    with tempfile.TemporaryDirectory() as work:
        exe = build_basisu(work)
        pattern = os.path.join(KTX2, "pattern.png")
        opaque = os.path.join(work, "pattern_opaque.png")
        Image.open(pattern).convert("RGB").save(opaque)
        for src, name, extra in [(pattern, "pattern_etc1s.ktx2", []),
                                 (pattern, "pattern_etc1s_mips.ktx2", ["-mipmap"]),
                                 (opaque, "pattern_etc1s_opaque.ktx2", [])]:
            basisu(exe, "-ktx2", src, "-output_file", os.path.join(KTX2, name), *extra, cwd=work)
        for src, ktx2, name, extra in [
                (pattern, "pattern_etc1s.ktx2", "pattern_etc1s_reference.png", []),
                (pattern, "pattern_etc1s_mips.ktx2", "pattern_etc1s_mips_reference.png", ["-mipmap"]),
                (opaque, "pattern_etc1s_opaque.ktx2", "pattern_etc1s_opaque_reference.png", [])]:
            rgba = reference(exe, src, work, extra)
            check_etc1_equals(exe, os.path.join(KTX2, ktx2), rgba, work)
            Image.fromarray(rgba, "RGBA").save(os.path.join(KTX2, name))

        ktx2_glb(exe, os.path.join(COMPRESSED, "avocado_small.glb"), os.path.join(COMPRESSED, "avocado_etc1s.glb"), [], work)
    print("wrote tests/data/ktx2/pattern_etc1s*.ktx2, their references, and tests/data/compressed/avocado_etc1s.glb")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "encode":
        # python3 tools/make_etc1s_test_files.py encode IN.glb OUT.glb [--uastc] [--mipmap]: any
        # .glb's images as KTX2, ETC1S or UASTC, with or without their mip chains (how
        # docs/performance.md's compressed SheenChairs were made).
        mode = (["-uastc"] if "--uastc" in sys.argv else []) + (["-mipmap"] if "--mipmap" in sys.argv else [])
        with tempfile.TemporaryDirectory() as work:
            ktx2_glb(build_basisu(work), sys.argv[2], sys.argv[3], mode, work)
    else:
        main()
