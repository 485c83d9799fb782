// Element index of this invocation in a gfx::dispatch_1d() grid (runtime/gfx/dispatch.h): work groups are
// laid out row-major over a 2D grid (GL guarantees only 65,535 groups per dimension), so the index is
// (row * groups per row) * local size + the invocation's x. The last row is partly empty: the caller
// bounds-checks the index against its element count. Needs the local size declared before the include's
// use (gl_WorkGroupSize is a compile-time constant then).
#ifndef SFFD_DISPATCH_GLSL
#define SFFD_DISPATCH_GLSL

uint sffd_dispatch_index() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x + gl_GlobalInvocationID.x;
}

#endif
