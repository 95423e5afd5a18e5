#version 460
// G-buffer pass, fragment stage, glTF materials alone (include/gbuffer_main.glsl with
// MATERIAL_KIND fixed at 2u).
#define GBUFFER_KIND 2u
#include "gbuffer_main.glsl"
