// The weave (docs/fabric-model.md §2): what lies under a point, and the exact coverage of an
// axis-aligned box footprint.
//
// Twin of src/fabric/coverage.rs (`reference::weave`, module `single`, f32), line for line, same names.
//
// Coordinates are in cells: x = u·cell_per_uv (= u/(s_p/2)). Reduce them to the repeat before
// they reach f32 (an f32 u = 1e7 has lost the pattern): weave_point and weave_box then take any
// value, negative included. In cell (i, j), local (a, b) ∈ [0, 1)², g = gap, d = shadow_dist:
// the weft of row j occupies g < b < 1-g, the warp of column i g < a < 1-g; where both cross, the
// cell's top thread shows; where neither passes, and on cell borders, it is gap. A thread is
// darkened (factor 1 - shadow_strength) within d, along its length, of the edge of a thread that
// crosses over it. Results are (c_warp, c_weft, s_warp, s_weft): the area fractions of warp and
// weft on top, and the same areas weighted by the diffuse shadow factor, as fabric_brdf takes
// them. All four are areas, so they average exactly over any footprint.
#ifndef WEFT_WEAVE_GLSL
#define WEFT_WEAVE_GLSL

#include "fabric.glsl"

// Boxes narrower than this (cells) are their centre point: below it an f32 box is rounding noise
// (ulp(8) = 1e-6), and 1/(wx·wy) stays far from overflow.
#define WEAVE_MIN_BOX 1e-6
// The most pieces along a footprint's longer edge (weave_pieces; Rust: Footprint::MAX_PIECES).
#define WEAVE_MAX_PIECES 4u


// Rust twin: weft::reference::weave::single::Weave. Built from a GpuFabric or from WeavePush.
struct Weave {
    uint pattern_lo;       // bit 8j+i = cell (i, j) weft-up, rows 0..3
    uint pattern_hi;       // rows 4..7
    uint cols;             // cells along u, 1..8
    uint rows;             // cells along v, 1..8
    float gap;             // s_g/s_p: half the gap, in cells, [0, 1/2]
    float shadow_dist;     // shadow_width/2, in cells, [0, 1/2]
    float shadow_strength; // [0, 1]
};

// The weave of a material (Rust: Weave::from_gpu).
Weave weave_from_fabric(GpuFabric m) {
    return Weave(m.pattern_lo, m.pattern_hi, m.cols, m.rows, m.gap, m.shadow_dist, m.shadow_strength);
}

// Texture coordinates to cells: uv·cell_per_uv (reduce uv per repeat first).
vec2 weave_cells(vec2 uv, float cell_per_uv) {
    return vec2(uv.x * cell_per_uv, uv.y * cell_per_uv);
}

// Where to sample the weave texture (one repeat, REPEAT addressing) for texture coordinates uv.
vec2 weave_st(vec2 uv, float cell_per_uv, uint cols, uint rows) {
    return vec2(uv.x * cell_per_uv / float(cols), uv.y * cell_per_uv / float(rows));
}

// Is cell (i, j) weft-up? i < cols, j < rows.
bool weave_weft_up(Weave w, uint i, uint j) {
    uint bit = 8u * j + i;
    uint word = bit < 32u ? w.pattern_lo >> bit : w.pattern_hi >> (bit - 32u);
    return (word & 1u) != 0u;
}

// x floor-modulo period, in [0, period). A result that rounds up to period (a tiny negative x)
// is returned as 0: the point rounds onto the border.
float weave_wrap(float x, float period) {
    float r = x - period * floor(x / period);
    if (r < 0.0) {
        r += period;
    }
    if (r >= period) {
        r = 0.0;
    }
    return r;
}

// Measure of {x in [x0, x1] : x mod period in [lo, hi]}, 0 <= lo <= hi <= period: the difference
// of the periodic antiderivative G(x) = n·(hi - lo) + clamp(r - lo, 0, hi - lo), x = n·period + r.
float weave_measure(float x0, float x1, float period, float lo, float hi) {
    float n0 = floor(x0 / period);
    float n1 = floor(x1 / period);
    float r0 = x0 - n0 * period;
    float r1 = x1 - n1 * period;
    float len = hi - lo;
    return (n1 - n0) * len + clamp(r1 - lo, 0.0, len) - clamp(r0 - lo, 0.0, len);
}

// The weave at the point (x, y) (cells): (c_warp, c_weft, s_warp, s_weft), one coverage 1 (or
// both 0: gap), and that thread's diffuse shadow factor in its s (the other 0).
vec4 weave_point(Weave w, float x, float y) {
    float xr = weave_wrap(x, float(w.cols));
    float yr = weave_wrap(y, float(w.rows));
    float fi = floor(xr);
    float fj = floor(yr);
    float a = xr - fi;
    float b = yr - fj;
    if (a == 0.0 || b == 0.0) {
        return vec4(0.0);
    }
    uint i = uint(fi);
    uint j = uint(fj);
    float g = w.gap;
    float dive = clamp(w.shadow_dist - g, 0.0, 0.5);
    float q = max(g - w.shadow_dist, 0.0);
    float dark = 1.0 - w.shadow_strength;
    bool in_weft_band = b > g && b < 1.0 - g;
    bool in_warp_band = a > g && a < 1.0 - g;
    if (weave_weft_up(w, i, j)) {
        if (in_weft_band) {
            bool left = !weave_weft_up(w, (i + w.cols - 1u) % w.cols, j);
            bool right = !weave_weft_up(w, (i + 1u) % w.cols, j);
            bool shadowed = (left && a < dive) || (right && a > 1.0 - dive);
            return vec4(0.0, 1.0, 0.0, shadowed ? dark : 1.0);
        }
        if (in_warp_band) {
            bool shadowed = b > q && b < 1.0 - q;
            return vec4(1.0, 0.0, shadowed ? dark : 1.0, 0.0);
        }
    } else {
        if (in_warp_band) {
            bool below = weave_weft_up(w, i, (j + w.rows - 1u) % w.rows);
            bool above = weave_weft_up(w, i, (j + 1u) % w.rows);
            bool shadowed = (below && b < dive) || (above && b > 1.0 - dive);
            return vec4(1.0, 0.0, shadowed ? dark : 1.0, 0.0);
        }
        if (in_weft_band) {
            bool shadowed = a > q && a < 1.0 - q;
            return vec4(0.0, 1.0, 0.0, shadowed ? dark : 1.0);
        }
    }
    return vec4(0.0);
}

// The exact coverage of the box [x0, x1] × [y0, y1] (cells). Reduce x0, y0 to the repeat first;
// any size of box works. A box narrower than WEAVE_MIN_BOX in either direction (or with NaN
// corners) is its centre point.
vec4 weave_box(Weave w, float x0, float y0, float x1, float y1) {
    float wx = x1 - x0;
    float wy = y1 - y0;
    if (!(wx >= WEAVE_MIN_BOX && wy >= WEAVE_MIN_BOX)) {
        return weave_point(w, 0.5 * (x0 + x1), 0.5 * (y0 + y1));
    }
    float px = float(w.cols);
    float py = float(w.rows);
    float g = w.gap;
    float dive = clamp(w.shadow_dist - g, 0.0, 0.5);
    float q = max(g - w.shadow_dist, 0.0);
    // Per column i, measures along x of: the whole cell, the warp band (g, 1-g), the dive zones
    // (0, dive) and (1-dive, 1) of a top thread, the under-thread strips (0, g) ∪ (1-g, 1) and
    // their shadowed parts (q, g) ∪ (1-g, 1-q).
    float x_full[8];
    float x_band[8];
    float x_low[8];
    float x_high[8];
    float x_strip[8];
    float x_strip_dark[8];
    for (uint i = 0u; i < w.cols; i++) {
        float c = float(i);
        uint k = i;
        x_full[k] = weave_measure(x0, x1, px, c, c + 1.0);
        x_band[k] = weave_measure(x0, x1, px, c + g, c + 1.0 - g);
        x_low[k] = weave_measure(x0, x1, px, c, c + dive);
        x_high[k] = weave_measure(x0, x1, px, c + 1.0 - dive, c + 1.0);
        x_strip[k] = weave_measure(x0, x1, px, c, c + g) + weave_measure(x0, x1, px, c + 1.0 - g, c + 1.0);
        x_strip_dark[k] = weave_measure(x0, x1, px, c + q, c + g) + weave_measure(x0, x1, px, c + 1.0 - g, c + 1.0 - q);
    }
    float warp = 0.0;
    float weft = 0.0;
    float dark_warp = 0.0;
    float dark_weft = 0.0;
    for (uint j = 0u; j < w.rows; j++) {
        float r = float(j);
        float y_full = weave_measure(y0, y1, py, r, r + 1.0);
        if (!(y_full > 0.0)) {
            continue;
        }
        float y_band = weave_measure(y0, y1, py, r + g, r + 1.0 - g);
        float y_low = weave_measure(y0, y1, py, r, r + dive);
        float y_high = weave_measure(y0, y1, py, r + 1.0 - dive, r + 1.0);
        float y_strip = weave_measure(y0, y1, py, r, r + g) + weave_measure(y0, y1, py, r + 1.0 - g, r + 1.0);
        float y_strip_dark = weave_measure(y0, y1, py, r + q, r + g) + weave_measure(y0, y1, py, r + 1.0 - g, r + 1.0 - q);
        uint below = (j + w.rows - 1u) % w.rows;
        uint above = (j + 1u) % w.rows;
        for (uint i = 0u; i < w.cols; i++) {
            uint k = i;
            if (weave_weft_up(w, i, j)) {
                // Weft on top across the cell; the warp shows in the strips beside it.
                bool left = !weave_weft_up(w, (i + w.cols - 1u) % w.cols, j);
                bool right = !weave_weft_up(w, (i + 1u) % w.cols, j);
                float dive_x = (left ? x_low[k] : 0.0) + (right ? x_high[k] : 0.0);
                weft += x_full[k] * y_band;
                warp += x_band[k] * y_strip;
                dark_weft += dive_x * y_band;
                dark_warp += x_band[k] * y_strip_dark;
            } else {
                bool lo = weave_weft_up(w, i, below);
                bool hi = weave_weft_up(w, i, above);
                float dive_y = (lo ? y_low : 0.0) + (hi ? y_high : 0.0);
                warp += x_band[k] * y_full;
                weft += x_strip[k] * y_band;
                dark_warp += x_band[k] * dive_y;
                dark_weft += x_strip_dark[k] * y_band;
            }
        }
    }
    float inv_area = 1.0 / (wx * wy);
    float c_warp = clamp(warp * inv_area, 0.0, 1.0);
    float c_weft = clamp(weft * inv_area, 0.0, 1.0);
    float s_warp = clamp((warp - w.shadow_strength * dark_warp) * inv_area, 0.0, c_warp);
    float s_weft = clamp((weft - w.shadow_strength * dark_weft) * inv_area, 0.0, c_weft);
    return vec4(c_warp, c_weft, s_warp, s_weft);
}

// Pieces for weave_parallelogram, along dx and along dy: the footprint's bounding box is exact
// when the footprint is aligned with the weave (its box is itself) and harmless when it spans
// many cells (the weave is averaged away either way); in between, the box's shape differs from
// the parallelogram's and blurs the weave. Cutting the footprint into pieces (`most` times the
// shorter edge's share of the longer along the shorter, at least one, and along the longer as
// many as keep the pieces about as long as wide, `most` to WEAVE_MAX_PIECES: a grazing footprint
// six times longer than wide is cut 4 x 1) makes each piece's box fit it better. dx, dy: the
// footprint's edges, in cells. Rust twin:
// reference::weave::single::weave_pieces.
uvec2 weave_pieces(vec2 dx, vec2 dy, uint most) {
    float box_area = (abs(dx.x) + abs(dy.x)) * (abs(dx.y) + abs(dy.y));
    float area = abs(dx.x * dy.y - dx.y * dy.x);
    float extent = max(abs(dx.x) + abs(dy.x), abs(dx.y) + abs(dy.y));
    if (!(box_area > 1.02 * area) || !(extent < 4.0) || most <= 1u) {
        return uvec2(1u);
    }
    float lx = length(dx);
    float ly = length(dy);
    float ratio = max(lx, ly) / min(lx, ly);
    float shorter = clamp(floor(float(most) / ratio + 0.5), 1.0, float(most));
    uint longer = uint(clamp(floor(shorter * ratio + 0.5), float(most), float(max(most, WEAVE_MAX_PIECES))));
    return lx >= ly ? uvec2(longer, uint(shorter)) : uvec2(uint(shorter), longer);
}

// The half-extent of each piece's box when the parallelogram spanned by dx, dy is cut into
// k.x x k.y equal pieces: the piece's bounding box shrunk about its centre to the piece's area.
// Scale-free per axis (cells or repeats alike). Rust twin: reference::weave::single::weave_piece_half.
vec2 weave_piece_half(vec2 dx, vec2 dy, uvec2 k) {
    vec2 kf = vec2(max(k, uvec2(1u)));
    vec2 half_box = (abs(dx) / kf.x + abs(dy) / kf.y) * 0.5;
    float box_area = 4.0 * half_box.x * half_box.y;
    float area = abs(dx.x * dy.y - dx.y * dy.x) / (kf.x * kf.y);
    return half_box * (box_area > area && area > 0.0 ? sqrt(area / box_area) : 1.0);
}

// The centre of piece n (row by row: i = n mod k.x, j = n / k.x) when the parallelogram
// {c + a·dx + b·dy : a, b in [-1/2, 1/2]} is cut into k.x x k.y equal pieces. The pieces are
// one loop over n, not a loop in a loop: llvmpipe runs a loop's body once more under an empty
// mask after every lane has left, and a nested loop's inner loop once more per outer turn.
// Rust twin: reference::weave::single::weave_piece_centre.
vec2 weave_piece_centre(vec2 c, vec2 dx, vec2 dy, uvec2 k, uint n) {
    vec2 kf = vec2(max(k, uvec2(1u)));
    uint kx = max(k.x, 1u);
    return c + dx * ((float(n % kx) + 0.5) / kf.x - 0.5) + dy * ((float(n / kx) + 0.5) / kf.y - 0.5);
}

// The coverage of the parallelogram {c + a·dx + b·dy : a, b in [-1/2, 1/2]} (cells; c reduced to
// the repeat) cut into k.x x k.y equal pieces: the mean of the exact box coverages of one box per
// piece, its bounding box shrunk about its centre to the piece's area (equal areas, and every
// coverage is an area, so the mean stands for the whole). Rust twin:
// reference::weave::single::weave_parallelogram.
vec4 weave_parallelogram(Weave w, vec2 c, vec2 dx, vec2 dy, uvec2 k) {
    vec2 kf = vec2(max(k, uvec2(1u)));
    vec2 half_box = weave_piece_half(dx, dy, k);
    vec4 sum = vec4(0.0);
    for (uint n = 0u; n < k.x * k.y; ++n) {
        vec2 p = weave_piece_centre(c, dx, dy, k, n);
        vec2 lo = p - half_box;
        vec2 hi = p + half_box;
        sum += weave_box(w, lo.x, lo.y, hi.x, hi.y);
    }
    return sum / (kf.x * kf.y);
}

#endif // WEFT_WEAVE_GLSL
