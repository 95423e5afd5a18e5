#version 460
// The occlusion pass, step 3 of 3, at half resolution: the mean of the 4 x 4 estimates of
// occlusion.frag around each (one of each of its pattern's 16 turns, so 16 x SLICES directions),
// each weighted by how close its view distance lies to the plane that the estimates' distances
// make around this one (their smaller one-sided difference to each neighbour, so an edge does not
// tilt it): a floor seen at a grazing angle blurs along both axes, while an edge does not blur
// into what is behind it. The lighting pass brings it to full resolution (lighting.frag's
// screen_visibility).
layout(set = 0, binding = 28) uniform sampler2D raw_occlusion;  // the occlusion pass's half-resolution estimates (RG16F: visibility, view distance; 0: empty), fetched per texel

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec2 out_visibility;  // the blurred visibility and the view distance (RG16F, half resolution), read by the lighting pass

float distance_at(ivec2 p, ivec2 size) {
    return texelFetch(raw_occlusion, clamp(p, ivec2(0), size - 1), 0).g;
}

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
    ivec2 size = textureSize(raw_occlusion, 0);
    vec2 here = texelFetch(raw_occlusion, px, 0).rg;
    if (here.y <= 0.0) {
        out_visibility = vec2(1.0, 0.0);
        return;
    }
    float dx = slope(distance_at(px - ivec2(1, 0), size), here.y, distance_at(px + ivec2(1, 0), size));
    float dy = slope(distance_at(px - ivec2(0, 1), size), here.y, distance_at(px + ivec2(0, 1), size));
    float sum = 0.0;
    float weights = 0.0;
    for (int y = -2; y < 2; ++y) {
        for (int x = -2; x < 2; ++x) {
            vec2 s = texelFetch(raw_occlusion, clamp(px + ivec2(x, y), ivec2(0), size - 1), 0).rg;
            float expected = here.y + float(x) * dx + float(y) * dy;
            float w = s.y > 0.0 ? clamp(1.0 - abs(s.y - expected) / (0.02 * here.y), 0.0, 1.0) : 0.0;
            sum += w * s.x;
            weights += w;
        }
    }
    out_visibility = vec2(sum / max(weights, 1e-6), here.y);
}
