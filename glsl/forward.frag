#version 460
// Forward pass, fragment stage (alphaMode BLEND): drawn after the deferred lighting pass, over
// its HDR image, with gbuffer.vert, depth-tested against the opaque surfaces' depth and not
// writing it. Each fragment computes the surface gbuffer.frag would store (surface.glsl) and
// shades it at once as the lighting pass shades a G-buffer pixel (shade.glsl): the same lights,
// environment and shadows. Writes premultiplied radiance and the base colour's alpha, blended
// with ONE, ONE_MINUS_SRC_ALPHA (glTF's BLEND: colour·alpha + behind·(1 - alpha)). Transmissive
// surfaces (KHR_materials_transmission, _volume) are drawn here too: they read the backdrop.
#include "forward_main.glsl"
