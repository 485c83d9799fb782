#version 450 core
layout(local_size_x = 1) in;
#include "lib/bad.glsl"
void main() { int x = bad_value(); }
