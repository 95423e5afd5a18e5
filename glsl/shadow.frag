#version 460
// Shadow pass, fragment stage: nothing to write but depth, which the fixed function does.

void main() {
}
