#version 460
// G-buffer pass, fragment stage: samples the material's textures and writes the surface's
// attributes, for the kind of material its MATERIAL_KIND constant names, or any
// (include/gbuffer_main.glsl). Lighting happens later, in the lighting pass, from these targets.
#include "gbuffer_main.glsl"
