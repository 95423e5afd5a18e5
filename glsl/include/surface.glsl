// A surface's attributes from its material, as the G-buffer stores them: the material's textures
// sampled through their UV sets, the normal map, the weave's coverage over the pixel's footprint.
// gbuffer.frag writes them to the G-buffer targets; forward.frag (alphaMode BLEND) shades them
// at once with the same functions the lighting pass uses (shade.glsl), so a blended surface is lit
// exactly as an opaque one. The including shader declares `materials`, `fabrics` and the
// specialization constants ACCURACY, WEAVE_SOURCE, SHADING, FOOTPRINT_PIECES, VERTEX_COLORS,
// MATERIAL_KIND, TEXTURE_SLOTS and COAT (0 where no clear coat is drawn: its code is compiled out).

// Per material; missing textures are bound to 1x1 defaults (white, or a flat normal).
layout(set = 1, binding = 0) uniform sampler2D base_color_tex;  // base colour texture (sRGB)
layout(set = 1, binding = 1) uniform sampler2D metallic_roughness_tex;  // metallic-roughness texture (glTF: B metallic, G roughness)
layout(set = 1, binding = 2) uniform sampler2D normal_tex;  // tangent-space normal texture
layout(set = 1, binding = 3) uniform sampler2D emissive_tex;  // emissive texture (sRGB)
// The material's weave texture (fabric only): one pattern repeat, full mip chain, each texel the
// exact coverage (c_warp, c_weft, s_warp, s_weft) of its footprint; with WEAVE_SOURCE 2 or 3 its
// summed-area table instead (weave_sat_box below).
layout(set = 1, binding = 4) uniform sampler2D weave_tex;  // the material's weave texture (from weave.comp), trilinear, REPEAT
// Ambient occlusion (glTF occlusionTexture, red channel; white when the material has none).
layout(set = 1, binding = 5) uniform sampler2D occlusion_tex;  // ambient-occlusion texture (glTF occlusionTexture, R; white when none)
// KHR_materials_sheen, _specular and _anisotropy textures (white when the material has none).
layout(set = 1, binding = 6) uniform sampler2D sheen_color_tex;  // KHR_materials_sheen colour texture (sRGB; white when none)
layout(set = 1, binding = 7) uniform sampler2D sheen_roughness_tex;  // KHR_materials_sheen roughness texture (A; white when none)
layout(set = 1, binding = 8) uniform sampler2D specular_tex;  // KHR_materials_specular texture (A; white when none)
layout(set = 1, binding = 9) uniform sampler2D specular_color_tex;  // KHR_materials_specular colour texture (sRGB; white when none)
layout(set = 1, binding = 10) uniform sampler2D anisotropy_tex;  // KHR_materials_anisotropy texture (RG direction, B strength; any when the material has none)
// KHR_materials_transmission's texture (R) and KHR_materials_volume's thickness texture (G).
layout(set = 1, binding = 11) uniform sampler2D transmission_tex;  // KHR_materials_transmission texture (R; white when none)
layout(set = 1, binding = 12) uniform sampler2D thickness_tex;  // KHR_materials_volume thickness texture (G; white when none)
// KHR_materials_clearcoat's textures: the factor (R), the roughness (G), the coat's normal.
layout(set = 1, binding = 13) uniform sampler2D clearcoat_tex;  // KHR_materials_clearcoat texture (R: the factor; white when none)
layout(set = 1, binding = 14) uniform sampler2D clearcoat_roughness_tex;  // KHR_materials_clearcoat roughness texture (G; white when none)
layout(set = 1, binding = 15) uniform sampler2D clearcoat_normal_tex;  // KHR_materials_clearcoat normal texture (tangent space; a flat normal when none)
// KHR_materials_diffuse_transmission's textures: the factor (A) and the colour (RGB, sRGB).
layout(set = 1, binding = 16) uniform sampler2D diffuse_transmission_tex;  // KHR_materials_diffuse_transmission texture (A: the factor; white when none)
layout(set = 1, binding = 17) uniform sampler2D diffuse_transmission_color_tex;  // KHR_materials_diffuse_transmission colour texture (RGB, sRGB; white when none)
// KHR_materials_iridescence's textures: the factor (R) and the film's thickness (G).
layout(set = 1, binding = 18) uniform sampler2D iridescence_tex;  // KHR_materials_iridescence texture (R: the factor; white when none)
layout(set = 1, binding = 19) uniform sampler2D iridescence_thickness_tex;  // KHR_materials_iridescence thickness texture (G: from the minimum to the maximum thickness; white when none)

layout(push_constant, std430) uniform Draw {
    mat4 world;
    vec4 normal_matrix[3];
    uint material;
    float tangent_sign;
    uint flags;             // bit 0: the draw receives shadows
    uint world_base;        // gbuffer.vert's (the world light's offset)
} draw;

layout(location = 0) in vec3 in_world_pos;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;
layout(location = 4) in vec2 in_weave_uv;
layout(location = 5) in vec3 in_gouraud;
layout(location = 6) in vec2 in_uv1;
layout(location = 7) in vec4 in_color;
layout(location = 8) in vec4 in_world_light;


// The G-buffer's six values of one surface point (gbuffer.frag's outputs, before storage), and
// the base colour's alpha (factor x texture x vertex colour).
struct GSurface {
    vec4 albedo;    // RGBA8 sRGB: base colour, a: metallic
    uvec4 frame;    // RGBA16_UINT: octahedral normal (xy), tangent (zw), frame_encode
    vec4 surface;   // RGBA16F: roughness, material index, tangent sign, 1 if it receives shadows
    vec4 fabric;    // RGBA16F: c_warp, c_weft and each shadow-weighted (s_warp, s_weft)
    vec4 emissive;  // RGBA16F: emitted radiance, a: ambient occlusion
    vec4 specular;  // RGBA16F: the dielectric's F0 (rgb), specular weight
    float alpha;
    // Not in the G-buffer (transmissive surfaces are drawn by the transparent pass only):
    // KHR_materials_transmission and _volume: the transmission (factor × texture), the thickness
    // (world units: × texture × the draw's mean scale), the attenuation distance (0: infinite), the
    // index of refraction; and the attenuation colour (rgb).
    vec4 transmission;
    vec4 attenuation;
    // KHR_materials_clearcoat: the factor and roughness (× textures; 0, 0: no coat), and the
    // coat's normal (world, unit: the geometry's with the coat's own normal map, not the base's).
    vec4 coat;
    vec3 coat_normal;
    // KHR_materials_diffuse_transmission: the factor × texture (x; 0: none) and colour (yzw).
    vec4 diffuse_transmission;
    // KHR_materials_iridescence: the factor × texture (x; 0: none), the film's ior (y) and
    // thickness in nanometres (z).
    vec4 iridescence;
};
// Non-fabric materials reuse two fabric channels: fabric holds the sheen colour (rgb) and
// roughness (a), surface.z the anisotropy strength (and frame.zw its direction).

// The UVs of both sets and their screen derivatives, taken once in uniform control flow from the
// interpolants alone (see the weave's derivatives below for why not from anything loaded).
vec2 uv_d[6];

// Samples texture slot `slot` of material m through its own UV set and transform, with the
// derivatives carried through the transform's linear part. A slot no material of the scene has a
// texture in (TEXTURE_SLOTS, from the plan) is not sampled: every material has the 1x1 stand-in
// there (render::frame's defaults: flat normal for the two normal slots, white otherwise), whose
// value this returns exactly. `slot` is a constant at every call, so the sampling is compiled out.
vec4 sample_slot(sampler2D tex, Material m, uint slot) {
    if ((TEXTURE_SLOTS & (1u << slot)) == 0u) {
        return slot == SLOT_NORMAL || slot == SLOT_CLEARCOAT_NORMAL
            ? vec4(128.0 / 255.0, 128.0 / 255.0, 1.0, 1.0) : vec4(1.0);
    }
    vec4 r0 = m.uv[2u * slot];
    vec4 r1 = m.uv[2u * slot + 1u];
    uint set = r0.w > 0.5 ? 1u : 0u;
    vec2 uv = uv_d[3u * set];
    mat2 lin = mat2(r0.x, r1.x, r0.y, r1.y);
    vec2 st = lin * uv + vec2(r0.z, r1.z);
    return textureGrad(tex, st, lin * uv_d[3u * set + 1u], lin * uv_d[3u * set + 2u]);
}

// The tangent and bitangent of the clear coat's normal texture where its coordinates are not
// those the vertices' tangents follow: the surface's directions of increasing s and t of its own
// coordinates (its set through its transform's linear part), from the screen derivatives of
// those and of the position (dpdx, dpdy), in the plane of n; the bitangent along decreasing t on
// a front face (up the image: a glTF normal map's green points up, and the vertices' tangents'
// sign makes their bitangent so), turned with n on a back face (`facing` -1) as the vertices'
// frame is. Unchanged (t, b) where the coordinates do not vary on screen.
void coat_frame(Material m, vec3 dpdx, vec3 dpdy, vec3 n, float facing, inout vec3 t, inout vec3 b) {
    vec4 r0 = m.uv[2u * SLOT_CLEARCOAT_NORMAL];
    vec4 r1 = m.uv[2u * SLOT_CLEARCOAT_NORMAL + 1u];
    uint set = r0.w > 0.5 ? 1u : 0u;
    mat2 lin = mat2(r0.x, r1.x, r0.y, r1.y);
    vec2 dx = lin * uv_d[3u * set + 1u];
    vec2 dy = lin * uv_d[3u * set + 2u];
    float det = dx.x * dy.y - dx.y * dy.x;
    if (!(abs(det) > 1e-30)) {
        return;
    }
    // dpdx = Ps dx.x + Pt dx.y, dpdy = Ps dy.x + Pt dy.y.
    vec3 ps = (dpdx * dy.y - dpdy * dx.y) / det;
    vec3 pt = (dpdy * dx.x - dpdx * dy.x) / det;
    vec3 ts = ps - n * dot(n, ps);
    if (!(dot(ts, ts) > 1e-30)) {
        return;
    }
    t = normalize(ts);
    b = facing * (dot(cross(n, t), pt) > 0.0 ? -1.0 : 1.0) * cross(n, t);
}

// The weave's summed-area table (WEAVE_SOURCE 2 filtered, 3 fetched; Rust twin
// weft::fabric::WeaveSat, which builds it): it spans R x R repeats (2, more for a weave of fewer
// than four cells a side: a box narrower than R - 1 repeats, its corner in the first repeat, lies
// inside, and R - 1 repeats hold four cells, the widest footprint weave_pieces cuts). With W x H
// texels per repeat, texel (i, j), i <= RW, j <= RH, is the integral over [0, i/W] x [0, j/H] (a
// repeat has area 1) of the coverage minus its mean; texel (RW + 1, 0) the mean, texel (RW + 1, 1)
// R. The table at q in texel-corner units, bilinear between the four corners around it (exact
// for the texel-averaged coverage): by the sampler, or where the device cannot filter RGBA32F
// (Vulkan makes it optional) by four texel fetches.
// A summed-area table's texel: the weave texture's (src = SAT_WEAVE) or, from the thread-colour
// buffer, that of the table starting at vec4 `src` (a row of `size.x` texels after another).
#define SAT_WEAVE 0xffffffffu
vec4 sat_texel(uint src, ivec2 size, ivec2 i) {
    return src == SAT_WEAVE ? texelFetch(weave_tex, i, 0) : thread_colours[src + uint(i.y * size.x + i.x)];
}

// The mean of a table's value (texel (RW + 1, 0)). Rust twin: WeaveSat::mean.
vec4 sat_mean(uint src, ivec2 size) {
    return sat_texel(src, size, ivec2(size.x - 1, 0));
}

// R, the repeats a table spans along each axis (texel (RW + 1, 1)). Rust twin: WeaveSat::repeats.
float sat_repeats(uint src, ivec2 size) {
    return sat_texel(src, size, ivec2(size.x - 1, 1)).x;
}

// W x H: the weave table's texels per repeat (level 0 of the weave texture).
vec2 weave_sat_repeat_texels() {
    ivec2 size = textureSize(weave_tex, 0);
    return vec2(size - ivec2(2, 1)) / sat_repeats(SAT_WEAVE, size);
}

vec4 sat_corner(uint src, ivec2 size, vec2 q) {
    if (WEAVE_SOURCE == 2u && src == SAT_WEAVE) {
        // The device filters RGBA32F: the sampler's bilinear filter between texel centres.
        return textureLod(weave_tex, (q + 0.5) / vec2(size), 0.0);
    }
    ivec2 n = size - ivec2(2, 1);
    ivec2 i = clamp(ivec2(floor(q)), ivec2(0), n - 1);
    vec2 f = clamp(q - vec2(i), 0.0, 1.0);
    vec4 a = sat_texel(src, size, i);
    vec4 b = sat_texel(src, size, i + ivec2(1, 0));
    vec4 c = sat_texel(src, size, i + ivec2(0, 1));
    vec4 d = sat_texel(src, size, i + ivec2(1, 1));
    return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

// Where the box [lo, hi] of st (a repeat is 1 unit) lies in a table of r x r repeats: lo
// reduced into the first repeat, hi = r X + u1 (X whole tables); q0, q1 the corners in
// texel-corner units. Rust twin: WeaveSat::place.
void sat_place(ivec2 size, float r, vec2 lo, vec2 hi, out vec2 q0, out vec2 q1, out vec2 whole) {
    vec2 n = vec2(size - ivec2(2, 1));
    vec2 l = lo - floor(lo);
    vec2 h = l + (hi - lo);
    whole = floor(h / r);
    q0 = l * n / r;
    q1 = (h - r * whole) * n / r;
}

// The four corners' part of the integral of the value minus its mean over [lo, hi],
// T(u1,v1) - T(u1,v0) - T(u0,v1) + T(u0,v0): all of it for a box narrower than r - 1 repeats.
// Rust twin: WeaveSat::box_corners.
vec4 sat_corners(uint src, ivec2 size, float r, vec2 lo, vec2 hi) {
    vec2 q0, q1, whole;
    sat_place(size, r, lo, hi, q0, q1, whole);
    return sat_corner(src, size, q1) - sat_corner(src, size, vec2(q1.x, q0.y))
         - sat_corner(src, size, vec2(q0.x, q1.y)) + sat_corner(src, size, q0);
}

// The whole tables' part, X (T(r,v1) - T(r,v0)) + Y (T(u1,r) - T(u0,r)) (a whole table of the
// value minus its mean is 0): 0 for a box narrower than r - 1 repeats. Rust twin:
// WeaveSat::box_whole.
vec4 sat_whole(uint src, ivec2 size, float r, vec2 lo, vec2 hi) {
    vec2 q0, q1, whole;
    sat_place(size, r, lo, hi, q0, q1, whole);
    vec2 n = vec2(size - ivec2(2, 1));
    vec4 sum = vec4(0.0);
    if (whole.x > 0.0) {
        sum += whole.x * (sat_corner(src, size, vec2(n.x, q1.y)) - sat_corner(src, size, vec2(n.x, q0.y)));
    }
    if (whole.y > 0.0) {
        sum += whole.y * (sat_corner(src, size, vec2(q1.x, n.y)) - sat_corner(src, size, vec2(q0.x, n.y)));
    }
    return sum;
}

// The mean over the box [lo, hi] of st (any size and place): the table's mean (texel (RW + 1, 0))
// plus the corners' and whole tables' parts over the box's area. Rust twin: WeaveSat::box_mean.
vec4 sat_box(uint src, ivec2 size, vec2 lo, vec2 hi) {
    float r = sat_repeats(src, size);
    vec2 ext = hi - lo;
    return sat_mean(src, size)
        + (sat_corners(src, size, r, lo, hi) + sat_whole(src, size, r, lo, hi)) / max(ext.x * ext.y, 1e-30);
}

// The weave's mean coverage over the box [lo, hi] of st.
vec4 weave_sat_box(vec2 lo, vec2 hi) {
    return sat_box(SAT_WEAVE, textureSize(weave_tex, 0), lo, hi);
}

// Thread-by-thread colours (FABRIC_FLAG_THREAD_COLOURS; weft::fabric::ThreadColourTable builds
// the record at f.colours): vec4 0 = (warp colours, weft colours, the colour repeat's cells along
// u and v), 1 = (texels per cell, the table's width and height, 0), then the warp and the weft
// colours, then a summed-area table (the weave's layout) over 2 x 2 colour repeats of
// (s_warp·warp colour + s_weft·weft colour, s_warp + s_weft). thread_box: the mean of
// (s·colour, s) over the box [lo, hi] of st (weave repeats, reduced into the colour repeat):
// within one cell from the coverage `cov` of the box and the cell's two thread colours; over two
// to four cells from each cell's part of the box, its own coverage (weave_cells_coverage) and
// colours (both exact: the near field); over more, the table's mean over the box (the far field;
// its texels are 1/texels-per-cell of a cell).
vec4 weave_cells_coverage(GpuFabric f, vec2 a, vec2 b) {
    vec2 cells = vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
    return (WEAVE_SOURCE & 2u) != 0u ? weave_sat_box(a, b)
        : weave_box(weave_from_fabric(f), a.x * cells.x, a.y * cells.y, b.x * cells.x, b.y * cells.y);
}

vec4 thread_mix(uint base, uint nw, uint nf, vec2 cell, vec4 c) {
    vec3 cw = thread_colours[base + 2u + uint(mod(cell.x, float(nw)))].rgb;
    vec3 cf = thread_colours[base + 2u + nw + uint(mod(cell.y, float(nf)))].rgb;
    return vec4(c.z * cw + c.w * cf, c.z + c.w);
}

vec4 thread_box(GpuFabric f, vec2 lo, vec2 hi, vec4 cov) {
    uint base = f.colours;
    vec4 head = thread_colours[base];
    vec4 dims = thread_colours[base + 1u];
    uint nw = uint(head.x + 0.5);
    uint nf = uint(head.y + 0.5);
    vec2 cells = vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
    vec2 c0 = floor(lo * cells);
    vec2 span = max(ceil(hi * cells) - 1.0 - c0, vec2(0.0));
    vec4 mixed = vec4(0.0);
    if (all(equal(span, vec2(0.0)))) {
        mixed = thread_mix(base, nw, nf, c0, cov);
    } else if (all(lessThanEqual(span, vec2(1.0)))) {
        for (uint j = 0u; j <= uint(span.y); ++j) {
            for (uint i = 0u; i <= uint(span.x); ++i) {
                vec2 cell = c0 + vec2(float(i), float(j));
                vec2 a = max(lo, cell / cells);
                vec2 b = min(hi, (cell + 1.0) / cells);
                if (all(greaterThan(b, a))) {
                    mixed += (b.x - a.x) * (b.y - a.y) * thread_mix(base, nw, nf, cell, weave_cells_coverage(f, a, b));
                }
            }
        }
        mixed /= max((hi.x - lo.x) * (hi.y - lo.y), 1e-30);
    } else {
        // The table's box, in colour repeats (head.zw cells each).
        vec2 scale = cells / head.zw;
        mixed = sat_box(base + 2u + nw + nf, ivec2(dims.yz + 0.5), lo * scale, hi * scale);
    }
    return mixed;
}

// The thread colour of a footprint from its thread_box means: Σ s·colour / Σ s, `fallback` where
// no thread shows (the footprint in a gap).
vec3 thread_colour(vec4 mixed, vec3 fallback) {
    return mixed.a > 1e-4 ? clamp(mixed.rgb / mixed.a, 0.0, 1.0) : fallback;
}

// The surface at this fragment. Call it first in main, in uniform control flow: it takes the
// derivatives of the interpolants.
GSurface material_surface() {    GSurface s;

    uv_d = vec2[6](in_uv, dFdx(in_uv), dFdy(in_uv), in_uv1, dFdx(in_uv1), dFdy(in_uv1));
    Material m = materials[draw.material];

    // Shading frame. Interpolated normals can cancel out (or be NaN from a broken file that got
    // past the loader); fall back to the triangle's own normal.
    vec3 dpdx = dFdx(in_world_pos);
    vec3 dpdy = dFdy(in_world_pos);
    vec3 geometric = cross(dpdx, dpdy);
    vec3 n = in_normal;
    if (!(dot(n, n) > 1e-20)) {
        n = geometric;
    }
    n = dot(n, n) > 1e-30 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) {
        n = -n;
    }
    vec3 t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
    t = dot(t, t) > 1e-20 ? normalize(t) : any_tangent(n);
    float sign = in_tangent.w < 0.0 ? -1.0 : 1.0;
    vec3 b = sign * cross(n, t);

    // The coat's normal: the geometry's, or its own normal map, in the vertices' frame or (where
    // its coordinates are not those the tangents follow: coat.w) in the frame of its own
    // coordinates' screen derivatives.
    vec3 coat_normal = n;
    if (COAT != 0u && m.coat.z != 0.0) {
        vec3 ctn = sample_slot(clearcoat_normal_tex, m, SLOT_CLEARCOAT_NORMAL).xyz * 2.0 - 1.0;
        ctn.xy *= m.coat.z;
        vec3 ct = t;
        vec3 cb = b;
        if (m.coat.w > 0.5) {
            coat_frame(m, dpdx, dpdy, n, gl_FrontFacing ? 1.0 : -1.0, ct, cb);
        }
        vec3 cm = ct * ctn.x + cb * ctn.y + n * ctn.z;
        coat_normal = dot(cm, cm) > 1e-20 ? normalize(cm) : n;
    }

    vec3 tn = sample_slot(normal_tex, m, SLOT_NORMAL).xyz * 2.0 - 1.0;
    tn.xy *= m.emissive_normal.a;
    vec3 mapped = t * tn.x + b * tn.y + n * tn.z;
    if (dot(mapped, mapped) > 1e-20) {
        n = normalize(mapped);
        t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
        t = dot(t, t) > 1e-20 ? normalize(t) : any_tangent(n);
    }

    vec4 base_texel = sample_slot(base_color_tex, m, SLOT_BASE_COLOR);
    vec4 base = m.base_color * base_texel;
    if (VERTEX_COLORS != 0u) {
        base *= in_color;
    }
    vec4 mr = sample_slot(metallic_roughness_tex, m, SLOT_METALLIC_ROUGHNESS);
    float metallic = clamp(m.metallic_roughness.x * mr.b, 0.0, 1.0);
    float roughness = clamp(m.metallic_roughness.y * mr.g, 0.0, 1.0);
    if ((uint(m.extra.w + 0.5) & MATERIAL_SPEC_GLOSS) != 0u) {
        // KHR_materials_pbrSpecularGlossiness: roughness is 1 − glossiness × the texture's alpha.
        roughness = clamp(1.0 - m.metallic_roughness.y * mr.a, 0.0, 1.0);
    }
    vec3 emissive = m.emissive_normal.rgb * sample_slot(emissive_tex, m, SLOT_EMISSIVE).rgb;
    // The material's fabric (1-based; 0: glTF). A pipeline made for one kind of material
    // (MATERIAL_KIND, per draw) compiles the other kind's code out.
    uint fabric = uint(m.metallic_roughness.z + 0.5);
    fabric = MATERIAL_KIND == MATERIAL_KIND_GLTF ? 0u : MATERIAL_KIND == MATERIAL_KIND_WOVEN ? max(fabric, 1u) : fabric;

    // KHR_materials_anisotropy: the direction in the (normal-mapped) tangent frame, rotated, and
    // the strength; stored in place of the tangent and its sign (non-fabric only).
    float anisotropy = 0.0;
    vec3 frame_t = t;
    if (fabric == 0u && (uint(m.extra.w + 0.5) & MATERIAL_ANISOTROPY) != 0u) {
        vec2 dir = vec2(1.0, 0.0);
        anisotropy = m.extra.y;
        if ((uint(m.extra.w + 0.5) & MATERIAL_ANISOTROPY_TEXTURE) != 0u) {
            vec3 a = sample_slot(anisotropy_tex, m, SLOT_ANISOTROPY).rgb;
            dir = a.rg * 2.0 - 1.0;
            anisotropy *= a.b;
        }
        float c = cos(m.extra.z);
        float s = sin(m.extra.z);
        dir = vec2(c * dir.x - s * dir.y, s * dir.x + c * dir.y);
        vec3 bt = sign * cross(n, t);
        vec3 a = t * dir.x + bt * dir.y;
        a -= n * dot(n, a);
        frame_t = dot(a, a) > 1e-20 ? normalize(a) : t;
        if (!(dot(a, a) > 1e-20)) {
            anisotropy = 0.0;
        }
    }

    s.albedo = vec4(clamp(base.rgb, 0.0, 1.0), metallic);
    if (fabric > 0u) {
        // The fabric's albedo target holds its thread texture's filtered value (white without
        // one), which the lighting pass multiplies over the thread colours (fabric_tinted). The
        // base colour factor is not in it: on a woven material it is the fallback's far-field
        // albedo (docs/fabric-on-assets.md), and the thread colours replace it.
        uint ff = fabrics[fabric - 1u].flags;
        vec3 tint = vec3(1.0);
        if ((ff & FABRIC_FLAG_TEXTURE_BASE_COLOR) != 0u) {
            tint = base_texel.rgb;
        } else if ((ff & FABRIC_FLAG_TEXTURE_SHEEN_COLOR) != 0u) {
            tint = sample_slot(sheen_color_tex, m, SLOT_SHEEN_COLOR).rgb;
        }
        if (VERTEX_COLORS != 0u) {
            tint *= in_color.rgb;
        }
        s.albedo = vec4(clamp(tint, 0.0, 1.0), 0.0);
    }
    s.frame = frame_encode(oct_encode(n), oct_encode(frame_t));
    s.surface = vec4(roughness, float(draw.material), fabric > 0u ? sign : clamp(anisotropy, 0.0, 1.0),
                      (draw.flags & 1u) != 0u ? 1.0 : 0.0);
    // KHR_materials_specular with KHR_materials_ior: F0 = min(F0(ior) · colour, 1), weight.
    vec3 spec_color = m.specular.rgb * sample_slot(specular_color_tex, m, SLOT_SPECULAR_COLOR).rgb;
    float spec_weight = clamp(m.specular.a * sample_slot(specular_tex, m, SLOT_SPECULAR).a, 0.0, 1.0);
    s.specular = vec4(min(vec3(m.extra.x) * spec_color, vec3(1.0)), spec_weight);
    // The weave is sampled here, with the UV derivatives, because only this pass has them:
    // trilinear filtering of exact coverages gives the footprint's area fractions. Derivatives are
    // taken of the interpolated UV alone, before any branch: derivatives in non-uniform control
    // flow are undefined, and on lavapipe buffer loads read 0 in helper invocations, so the
    // derivative of anything loaded from a buffer is garbage in quads cut by a triangle edge.
    GpuFabric f = fabrics[max(fabric, 1u) - 1u];
    vec2 uv_dx = dFdx(in_weave_uv);
    vec2 uv_dy = dFdy(in_weave_uv);
    vec2 st_scale = f.cell_per_uv / vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
    vec2 st = in_weave_uv * st_scale;
    vec2 st_dx = uv_dx * st_scale;
    vec2 st_dy = uv_dy * st_scale;
    // KHR_materials_sheen (non-fabric): colour and roughness.
    s.fabric = vec4(0.0);
    if (fabric == 0u && max(m.sheen.r, max(m.sheen.g, m.sheen.b)) > 0.0) {
        vec3 sheen = m.sheen.rgb * sample_slot(sheen_color_tex, m, SLOT_SHEEN_COLOR).rgb;
        float sheen_roughness = m.sheen.a * sample_slot(sheen_roughness_tex, m, SLOT_SHEEN_ROUGHNESS).a;
        s.fabric = vec4(clamp(sheen, 0.0, 1.0), clamp(sheen_roughness, 0.0, 1.0));
    }
    if (fabric > 0u) {
        // The footprint as an axis-aligned box in st, half-extent `ext` (a repeat is 1 unit).
        vec2 ext = 0.5 * (abs(st_dx) + abs(st_dy));
        vec2 repeat_cells = vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
        // Thread-by-thread colours: st reduced into its colour repeat (a whole number of weave
        // repeats), and what takes fract(st) there; `mixed` the footprint's thread_box means.
        bool threads = THREAD_COLOURS != 0u && (f.flags & FABRIC_FLAG_THREAD_COLOURS) != 0u;
        vec2 colour_rep = threads ? thread_colours[f.colours].zw / repeat_cells : vec2(1.0);
        vec2 colour_shift = st - colour_rep * floor(st / colour_rep) - fract(st);
        vec4 mixed = vec4(-1.0);
        if (ACCURACY == 3u) {
            // Supersampled: the lighting pass evaluates the analytic weave at N x N points of the
            // footprint, so it gets the footprint itself: st within its repeat, and the extent.
            s.fabric = vec4(fract(st), ext);
        } else if (ACCURACY == 0u) {
            // Nearest: one texel of level 0, no filtering (the summed-area table's box of it).
            ivec2 size = textureSize(weave_tex, 0);
            ivec2 texel = clamp(ivec2(fract(st) * vec2(size)), ivec2(0), size - 1);
            vec2 sat_n = weave_sat_repeat_texels();
            vec2 sat_lo = floor(fract(st) * sat_n) / sat_n;
            vec4 coverage = WEAVE_SOURCE == 1u
                ? weave_point(weave_from_fabric(f), fract(st.x) * repeat_cells.x, fract(st.y) * repeat_cells.y)
                : (WEAVE_SOURCE & 2u) != 0u ? weave_sat_box(sat_lo, sat_lo + 1.0 / sat_n)
                : texelFetch(weave_tex, texel, 0);
            s.fabric = clamp(coverage, 0.0, 1.0);
        } else {
            vec4 coverage;
            if (WEAVE_SOURCE == 1u) {
                // The footprint parallelogram spanned by the st derivatives, in cells.
                vec2 dx = st_dx * repeat_cells;
                vec2 dy = st_dy * repeat_cells;
                if (FOOTPRINT_PIECES == 0u) {
                    vec2 lo = (fract(st) - ext) * repeat_cells;
                    vec2 hi = (fract(st) + ext) * repeat_cells;
                    coverage = weave_box(weave_from_fabric(f), lo.x, lo.y, hi.x, hi.y);
                } else {
                    coverage = weave_parallelogram(weave_from_fabric(f), fract(st) * repeat_cells, dx, dy,
                                                   weave_pieces(dx, dy, FOOTPRINT_PIECES));
                }
            } else if ((WEAVE_SOURCE & 2u) != 0u) { // 2 or 3 (a bit test: spirq evaluates no ordering of spec constants)
                // The summed-area table: the footprint's box (or the same pieces as the analytic
                // weave's, each its own box), each box at least one texel of level 0 (there the
                // table's box is the texture's bilinear filter).
                vec2 c = fract(st);
                ivec2 sat_size = textureSize(weave_tex, 0);
                float sat_r = sat_repeats(SAT_WEAVE, sat_size);
                vec2 least = 0.5 / weave_sat_repeat_texels();
                uvec2 k = FOOTPRINT_PIECES == 0u ? uvec2(1u)
                    : weave_pieces(st_dx * repeat_cells, st_dy * repeat_cells, FOOTPRINT_PIECES);
                vec2 half_box = max(FOOTPRINT_PIECES == 0u ? ext : weave_piece_half(st_dx, st_dy, k), least);
                vec2 kf = vec2(k);
                // Only a footprint taken whole (k = 1 x 1) can be wider than the table less a
                // repeat (weave_pieces cuts none of four cells or more, and the table spans a
                // repeat more than four cells), so the whole tables' part is the first piece's
                // alone, taken once here rather than for every piece (lavapipe would run it for
                // each: it runs both sides of a branch).
                vec2 p0 = weave_piece_centre(c, st_dx, st_dy, k, 0u);
                vec4 whole0 = sat_whole(SAT_WEAVE, sat_size, sat_r, p0 - half_box, p0 + half_box);
                vec4 mean = sat_mean(SAT_WEAVE, sat_size);
                vec2 piece_ext = 2.0 * half_box;
                float inv_area = 1.0 / max(piece_ext.x * piece_ext.y, 1e-30);
                coverage = vec4(0.0);
                vec4 pieces_mixed = vec4(0.0);
                // One loop over the pieces (weave_piece_centre). (A loop with its test at the end,
                // which would save llvmpipe's extra masked turn, gave wrong coverages on Mesa
                // 22.3's lavapipe.)
                for (uint n = 0u; n < k.x * k.y; ++n) {
                    vec2 p = weave_piece_centre(c, st_dx, st_dy, k, n);
                    vec4 part = sat_corners(SAT_WEAVE, sat_size, sat_r, p - half_box, p + half_box);
                    vec4 piece = mean + (n == 0u ? part + whole0 : part) * inv_area;
                    coverage += piece;
                    if (threads) {
                        // Each piece's colour over the piece itself, with its coverage: the
                        // mean's Σ s equals the coverage's, so the lighting gets Σ s·colour.
                        pieces_mixed += thread_box(f, p - half_box + colour_shift, p + half_box + colour_shift, piece);
                    }
                }
                coverage /= kf.x * kf.y;
                mixed = pieces_mixed / (kf.x * kf.y);
            } else {
                // The same pieces, each a filtered probe of its own size: the filter's footprint
                // follows the parallelogram instead of spanning its bounding box (lavapipe has no
                // anisotropic filtering; where a device has it, each probe also gets it).
                uvec2 k = FOOTPRINT_PIECES == 0u ? uvec2(1u)
                    : weave_pieces(st_dx * repeat_cells, st_dy * repeat_cells, FOOTPRINT_PIECES);
                vec2 kf = vec2(k);
                // Each probe's filter a level sharper where the footprint is within a cell or so
                // (there the trilinear filter's own width, 2-3 texels of its level, would blur
                // the threads), relaxing to none by two cells (where it would alias).
                vec2 cells_extent = (abs(st_dx) + abs(st_dy)) * repeat_cells;
                float sharpen = FOOTPRINT_PIECES == 0u ? 1.0
                    : clamp(0.5 * max(cells_extent.x, cells_extent.y), 0.5, 1.0);
                vec2 pdx = st_dx / kf.x * sharpen;
                vec2 pdy = st_dy / kf.y * sharpen;
                coverage = vec4(0.0);
                for (uint n = 0u; n < k.x * k.y; ++n) {
                    vec2 p = weave_piece_centre(st, st_dx, st_dy, k, n);
                    coverage += textureGrad(weave_tex, p, pdx, pdy);
                }
                coverage /= kf.x * kf.y;
            }
            s.fabric = clamp(coverage, 0.0, 1.0);
        }
        if (threads) {
            if (mixed.a < 0.0) {
                // Not the summed-area table's pieces: the footprint's bounding box (a point for
                // nearest) and its coverage, of the exact weave.
                vec2 sc = fract(st) + colour_shift;
                vec2 half_ext = ACCURACY == 0u ? vec2(0.0) : ext;
                vec2 lo = sc - half_ext;
                vec2 hi = sc + half_ext;
                vec4 cov = ACCURACY == 0u ? s.fabric
                    : weave_box(weave_from_fabric(f), lo.x * repeat_cells.x, lo.y * repeat_cells.y,
                                hi.x * repeat_cells.x, hi.y * repeat_cells.y);
                mixed = thread_box(f, lo, hi, cov);
            }
            s.albedo.rgb *= thread_colour(mixed, vec3(1.0));
        }
    }
    if (SHADING == SHADING_GOURAUD) {
        emissive += in_gouraud;
    }
    // Occlusion = 1 + strength·(texel - 1) (glTF 2.0, occlusionTexture); the strength is in
    // metallic_roughness.w.
    float ao = clamp(1.0 + m.metallic_roughness.w * (sample_slot(occlusion_tex, m, SLOT_OCCLUSION).r - 1.0), 0.0, 1.0);
    s.emissive = vec4(max(emissive, vec3(0.0)), ao);
    s.alpha = base.a;
    s.transmission = vec4(0.0);
    s.attenuation = vec4(1.0, 1.0, 1.0, 0.0);
    s.coat = vec4(0.0);
    s.coat_normal = coat_normal;
    s.diffuse_transmission = vec4(0.0, 1.0, 1.0, 1.0);
    if (fabric == 0u && (uint(m.extra.w + 0.5) & MATERIAL_DIFFUSE_TRANSMISSION) != 0u) {
        float dt = m.diffuse_transmission.x * sample_slot(diffuse_transmission_tex, m, SLOT_DIFFUSE_TRANSMISSION).a;
        vec3 dc = m.diffuse_transmission.yzw * sample_slot(diffuse_transmission_color_tex, m, SLOT_DIFFUSE_TRANSMISSION_COLOR).rgb;
        s.diffuse_transmission = vec4(clamp(dt, 0.0, 1.0), max(dc, vec3(0.0)));
    }
    s.iridescence = vec4(0.0, 1.3, 0.0, 0.0);
    if (fabric == 0u && (uint(m.extra.w + 0.5) & MATERIAL_IRIDESCENCE) != 0u) {
        float factor = m.iridescence.x * sample_slot(iridescence_tex, m, SLOT_IRIDESCENCE).r;
        // Without a thickness texture the film is the maximum thick (the texture reads white).
        float thickness = mix(m.iridescence.z, m.iridescence.w,
                              sample_slot(iridescence_thickness_tex, m, SLOT_IRIDESCENCE_THICKNESS).g);
        s.iridescence = vec4(clamp(factor, 0.0, 1.0), m.iridescence.y, max(thickness, 0.0), 0.0);
    }
    if (COAT != 0u && fabric == 0u && (uint(m.extra.w + 0.5) & MATERIAL_CLEARCOAT) != 0u) {
        float factor = m.coat.x * sample_slot(clearcoat_tex, m, SLOT_CLEARCOAT).r;
        float rough = m.coat.y * sample_slot(clearcoat_roughness_tex, m, SLOT_CLEARCOAT_ROUGHNESS).g;
        s.coat = vec4(clamp(factor, 0.0, 1.0), clamp(rough, 0.0, 1.0), 0.0, 0.0);
    }
    if (fabric == 0u && (uint(m.extra.w + 0.5) & MATERIAL_TRANSMISSION) != 0u) {
        float amount = m.alpha.y * sample_slot(transmission_tex, m, SLOT_TRANSMISSION).r;
        float scale = (length(draw.world[0].xyz) + length(draw.world[1].xyz) + length(draw.world[2].xyz)) / 3.0;
        float thickness = m.alpha.z * sample_slot(thickness_tex, m, SLOT_THICKNESS).g * scale;
        s.transmission = vec4(clamp(amount, 0.0, 1.0), max(thickness, 0.0), m.alpha.w, m.volume.a);
        // w: KHR_materials_dispersion's spread of the volume's index across the rays.
        s.attenuation = vec4(m.volume.rgb, m.dispersion.x);
    }
    return s;
}
