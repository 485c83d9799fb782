// The one place that includes OpenGL. No loader: GLVND exports GL 4.5 core entry points directly.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
