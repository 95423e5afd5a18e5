#version 460
// The occlusion pass, step 3 of 3, at half resolution: the mean of the 4 x 4 estimates of
// occlusion.frag around each (one of each of its pattern's 16 turns, so 16 x SLICES directions),
// each weighted by how close its view distance lies to the plane that the estimates' distances
// make around this one (their smaller one-sided difference to each neighbour, so an edge does not
// tilt it): a floor seen at a grazing angle blurs along both axes, while an edge does not blur
// into what is behind it. The lighting pass brings it to full resolution (lighting.frag's
// screen_visibility). The occluders' bounced light (BOUNCE) takes the same weights.
layout(constant_id = 2) const uint BOUNCE = 0u;

layout(set = 0, binding = 28) uniform sampler2D raw_occlusion;  // the occlusion pass's half-resolution estimates (RG16F: visibility, view distance; 0: empty), gathered (clamped to the edge)

layout(set = 0, binding = 29) uniform sampler2D raw_bounce;  // the occlusion pass's half-resolution bounced light (RGBA16F: rgb), fetched (BOUNCE)

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec2 out_visibility;  // the blurred visibility and the view distance (RG16F, half resolution), read by the lighting pass
layout(location = 1) out vec4 out_bounce;      // the blurred bounced light (RGBA16F: rgb; 0 without BOUNCE), read by the lighting pass

// The difference towards the neighbours along one axis that is smaller in magnitude (an empty
// neighbour, distance 0, does not count).
float slope(float left, float here, float right) {
    float a = left > 0.0 ? here - left : 1e30;
    float b = right > 0.0 ? right - here : 1e30;
    float s = abs(a) < abs(b) ? a : b;
    return abs(s) < 1e29 ? s : 0.0;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec2 texel = 1.0 / vec2(textureSize(raw_occlusion, 0));
    // The 4 x 4 estimates from (-2, -2) to (1, 1) around this one, by four gathers of each
    // channel (the sampler clamps to the edge, as the fetches' clamp did): vis[y][x], dist[y][x].
    float vis[4][4];
    float dist[4][4];
    for (int qy = 0; qy < 2; ++qy) {
        for (int qx = 0; qx < 2; ++qx) {
            // The corner shared by the quad's texels (2qx - 2, 2qy - 2) to (2qx - 1, 2qy - 1).
            vec2 uv = (vec2(px) + vec2(2 * qx - 1, 2 * qy - 1)) * texel;
            vec4 r = textureGather(raw_occlusion, uv, 0);
            vec4 g = textureGather(raw_occlusion, uv, 1);
            // A gather's texels: w (0, 0), z (1, 0), x (0, 1), y (1, 1).
            vis[2 * qy][2 * qx] = r.w;
            vis[2 * qy][2 * qx + 1] = r.z;
            vis[2 * qy + 1][2 * qx] = r.x;
            vis[2 * qy + 1][2 * qx + 1] = r.y;
            dist[2 * qy][2 * qx] = g.w;
            dist[2 * qy][2 * qx + 1] = g.z;
            dist[2 * qy + 1][2 * qx] = g.x;
            dist[2 * qy + 1][2 * qx + 1] = g.y;
        }
    }
    float here = dist[2][2];
    if (here <= 0.0) {
        out_visibility = vec2(1.0, 0.0);
        out_bounce = vec4(0.0);
        return;
    }
    float dx = slope(dist[2][1], here, dist[2][3]);
    float dy = slope(dist[1][2], here, dist[3][2]);
    float sum = 0.0;
    vec3 bounce = vec3(0.0);
    float weights = 0.0;
    ivec2 last = textureSize(raw_bounce, 0) - 1;
    for (int y = 0; y < 4; ++y) {
        for (int x = 0; x < 4; ++x) {
            float expected = here + float(x - 2) * dx + float(y - 2) * dy;
            float d = dist[y][x];
            float w = d > 0.0 ? clamp(1.0 - abs(d - expected) / (0.02 * here), 0.0, 1.0) : 0.0;
            sum += w * vis[y][x];
            if (BOUNCE != 0u) {
                bounce += w * texelFetch(raw_bounce, clamp(px + ivec2(x - 2, y - 2), ivec2(0), last), 0).rgb;
            }
            weights += w;
        }
    }
    out_visibility = vec2(sum / max(weights, 1e-6), here);
    out_bounce = vec4(bounce / max(weights, 1e-6), 0.0);
}
