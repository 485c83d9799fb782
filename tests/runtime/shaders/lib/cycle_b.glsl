// b includes a: a cycle.
#include "../cycle_a.glsl"
