// Compiling and linking GLSL programs (needs a current GL context). Failures
// throw std::runtime_error carrying the driver's info log.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

namespace sim4cv::render {

GLuint LinkProgram(const char* vertex_source, const char* fragment_source);

// Location of the active uniform `name`; throws std::runtime_error if there is
// none, since a misspelt name would otherwise silently set nothing.
GLint RequireUniform(GLuint program, const char* name);

// Throws std::runtime_error naming `what` if GL has recorded an error.
void ThrowOnGlError(const char* what);

}  // namespace sim4cv::render
