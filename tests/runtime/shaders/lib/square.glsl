#pragma once
// Included twice by squares.comp's chain would be harmless: #pragma once.
#include "helper_once.glsl"
uint square(uint x) { return helper_mul(x, x); }
