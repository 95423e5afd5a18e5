#version 460
// Deferred lighting pass: one fullscreen triangle. Reads the G-buffer, sums every light's
// contribution with the material's BRDF, and writes linear HDR radiance: every kind of pixel its
// PIXEL_KINDS constant names (include/lighting_main.glsl).
#include "lighting_main.glsl"
