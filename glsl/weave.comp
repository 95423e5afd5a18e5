#version 460
// Builds one mip level of a weave texture: one full pattern repeat, so it tiles with REPEAT
// addressing. Texel (x, y) of a W×H level covers [x/W, (x+1)/W] × [y/H, (y+1)/H] of the repeat
// (row 0 is v = 0: sample at st = (u, v)·cell_per_uv / (cols, rows), no flip) and holds the
// EXACT coverage of that footprint: (c_warp, c_weft, s_warp, s_weft), see weave.glsl. Every level is
// computed this way, not by downsampling the one above, so the values stay linear in area and
// trilinear/anisotropic filtering of them is a correct footprint average.
//
// Dispatch ceil(W/8) × ceil(H/8) groups per level, one storage-image view of that level bound.
// CPU twin: weft::fabric::weave_texels_cpu.
#extension GL_GOOGLE_include_directive : require
#include "weave.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

// set 0, binding 0: the mip level being written (one-level view of an RGBA16F image).
layout(set = 0, binding = 0, rgba16f) uniform writeonly image2D weave_level;  // the mip level being written: a one-level view of the RGBA16F weave texture

// Rust twin: weft::fabric::WeavePush (36 bytes).
layout(push_constant) uniform WeavePush {
    uint pattern_lo;       // 0: bit 8j+i = cell (i, j) weft-up, rows 0..3
    uint pattern_hi;       // 4: rows 4..7
    uint cols;             // 8: cells along u, 1..8
    uint rows;             // 12: cells along v, 1..8
    float gap;             // 16: s_g/s_p, in cells
    float shadow_dist;     // 20: shadow_width/2, in cells
    float shadow_strength; // 24
    uint width;            // 28: this level's size in texels
    uint height;           // 32
} pc;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) {
        return;
    }
    Weave w = Weave(pc.pattern_lo, pc.pattern_hi, pc.cols, pc.rows, pc.gap, pc.shadow_dist, pc.shadow_strength);
    float sx = float(pc.cols) / float(pc.width);
    float sy = float(pc.rows) / float(pc.height);
    vec4 c = weave_box(w, float(p.x) * sx, float(p.y) * sy, float(p.x + 1u) * sx, float(p.y + 1u) * sy);
    imageStore(weave_level, ivec2(p), c);
}
