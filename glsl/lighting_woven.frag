#version 460
// Deferred lighting pass, the woven model's pixels alone (include/lighting_main.glsl with
// PIXEL_KINDS fixed at 2u). Drawn where the G-buffer's stencil says a pixel is woven.
#define LIGHTING_KINDS 2u
#include "lighting_main.glsl"
