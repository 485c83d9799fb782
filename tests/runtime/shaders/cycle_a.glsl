#version 450 core
#include "lib/cycle_b.glsl"
void main() {}
