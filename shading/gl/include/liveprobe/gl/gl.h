#pragma once
// The one include for GL functions: glad2's generated loader (GL 3.3 core). It works for both
// context backends (GLFW and OSMesa); never include <GL/gl.h> or call exported gl* symbols.
#include <glad/gl.h>
