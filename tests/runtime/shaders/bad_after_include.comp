#version 450 core
layout(local_size_x = 1) in;
#include "lib/helper_once.glsl"

void main() {
    undeclared_identifier = 3u;
}
