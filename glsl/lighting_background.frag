#version 460
// Deferred lighting pass, the empty pixels alone: the environment seen along the view ray, a
// colour, or transparent (include/lighting_main.glsl with PIXEL_KINDS fixed at 1u). Drawn where
// the G-buffer's stencil says a pixel is empty.
#define LIGHTING_KINDS 1u
#include "lighting_main.glsl"
