#version 450 core
layout(local_size_x = 1) in;
#include "lib/does_not_exist.glsl"
void main() {}
