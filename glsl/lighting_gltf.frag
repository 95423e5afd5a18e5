#version 460
// Deferred lighting pass, the glTF materials' pixels alone (include/lighting_main.glsl with
// PIXEL_KINDS fixed at 4u). Drawn where the G-buffer's stencil says a pixel is a glTF material's.
#define LIGHTING_KINDS 4u
#include "lighting_main.glsl"
