#version 460
// Forward pass, fragment stage, where no fabric is drawn forward: include/forward_main.glsl with
// the woven model compiled out (MATERIAL_KIND glTF, no fabric sheets).
#define FORWARD_GLTF 1
#include "forward_main.glsl"
