// OpenGL 3.3 core entry points. On Linux the GL library (libglvnd's libGL) exports every core
// function, so prototypes are enough (GL_GLEXT_PROTOTYPES is set for this target); no loader.
#pragma once

#include <GL/gl.h>
#include <GL/glext.h>
