#version 460
// Depth-only passes (the shadow maps, the G-buffer's depth pre-pass), fragment stage: nothing to
// write but depth, which the fixed function does.

void main() {
}
